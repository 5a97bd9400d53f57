#include "common/dds/identity_check.h"

#include <filesystem>
#include <memory>
#include <string_view>
#include <vector>

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>

#include "common/dds/participant.h"

namespace mrslam::dds {

namespace {

template <auto Free>
struct Deleter {
  template <typename T>
  void operator()(T* p) const {
    Free(p);
  }
};
using Bio = std::unique_ptr<BIO, Deleter<BIO_free_all>>;
using Certificate = std::unique_ptr<X509, Deleter<X509_free>>;
using Key = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY_free>>;
using Store = std::unique_ptr<X509_STORE, Deleter<X509_STORE_free>>;
using StoreContext = std::unique_ptr<X509_STORE_CTX, Deleter<X509_STORE_CTX_free>>;
using Pkcs7 = std::unique_ptr<PKCS7, Deleter<PKCS7_free>>;

[[noreturn]] void Fail(const std::string& path, const std::string& problem) {
  ERR_clear_error();
  throw DdsError("security file " + path + ": " + problem);
}

Bio Open(const std::string& path) {
  if (!std::filesystem::exists(path)) Fail(path, "missing (make it with scripts/security/make_identities.sh)");
  Bio bio(BIO_new_file(path.c_str(), "r"));
  if (!bio) Fail(path, "cannot be read");
  return bio;
}

Certificate ReadCertificate(const std::string& path) {
  Certificate cert(PEM_read_bio_X509(Open(path).get(), nullptr, nullptr, nullptr));
  if (!cert) Fail(path, "not a PEM certificate");
  return cert;
}

std::string Text(const Bio& bio) {
  char* data = nullptr;
  const long size = BIO_get_mem_data(bio.get(), &data);
  return size > 0 ? std::string(data, static_cast<std::size_t>(size)) : std::string();
}

// The subject in RFC 2253 order (CN=r1,O=MRSLAM,C=ES), as the permissions name it.
std::string Subject(const X509* cert) {
  Bio out(BIO_new(BIO_s_mem()));
  X509_NAME_print_ex(out.get(), X509_get_subject_name(cert), 0, XN_FLAG_RFC2253);
  return Text(out);
}

std::string CommonName(const X509* cert) {
  const X509_NAME* name = X509_get_subject_name(cert);
  const int index = X509_NAME_get_index_by_NID(name, NID_commonName, -1);
  if (index < 0) return {};
  const ASN1_STRING* value = X509_NAME_ENTRY_get_data(X509_NAME_get_entry(name, index));
  return {reinterpret_cast<const char*>(ASN1_STRING_get0_data(value)),
          static_cast<std::size_t>(ASN1_STRING_length(value))};
}

std::string TimeText(const ASN1_TIME* time) {
  Bio out(BIO_new(BIO_s_mem()));
  ASN1_TIME_print(out.get(), time);
  return Text(out);
}

Store TrustOnly(const X509* ca) {
  Store store(X509_STORE_new());
  if (!store || X509_STORE_add_cert(store.get(), const_cast<X509*>(ca)) != 1) {
    throw DdsError("cannot build an OpenSSL certificate store");
  }
  return store;
}

void CheckValidNow(const X509* cert, const std::string& path) {
  if (X509_cmp_current_time(X509_get0_notBefore(cert)) >= 0) {
    Fail(path, "certificate not valid before " + TimeText(X509_get0_notBefore(cert)));
  }
  if (X509_cmp_current_time(X509_get0_notAfter(cert)) <= 0) {
    Fail(path, "certificate expired on " + TimeText(X509_get0_notAfter(cert)));
  }
}

void CheckSignedBy(X509* cert, const X509* ca, const std::string& path, const std::string& ca_path) {
  const Store store = TrustOnly(ca);
  const StoreContext context(X509_STORE_CTX_new());
  if (!context || X509_STORE_CTX_init(context.get(), store.get(), cert, nullptr) != 1) {
    throw DdsError("cannot build an OpenSSL verification context");
  }
  if (X509_verify_cert(context.get()) != 1) {
    Fail(path, std::string("not issued by ") + ca_path + " (" +
                   X509_verify_cert_error_string(X509_STORE_CTX_get_error(context.get())) + ")");
  }
}

// The document a permissions-CA signature covers (S/MIME, signed with -text), or a failure.
std::string SignedDocument(const std::string& path, const X509* permissions_ca, const std::string& ca_path) {
  BIO* content = nullptr;
  const Bio in = Open(path);
  const Pkcs7 p7(SMIME_read_PKCS7(in.get(), &content));
  const Bio content_owner(content);
  if (!p7) Fail(path, "not an S/MIME signed document");
  const Store store = TrustOnly(permissions_ca);
  const Bio out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content, out.get(), PKCS7_TEXT) != 1) {
    Fail(path, "signature not verified by " + ca_path + " (signed by another CA, altered, or without -text?)");
  }
  return Text(out);
}

std::string Trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

// Every <subject_name> of a permissions document.
std::vector<std::string> GrantedSubjects(const std::string& document) {
  constexpr std::string_view kOpen = "<subject_name>";
  constexpr std::string_view kClose = "</subject_name>";
  std::vector<std::string> subjects;
  for (auto at = document.find(kOpen); at != std::string::npos; at = document.find(kOpen, at)) {
    at += kOpen.size();
    const auto end = document.find(kClose, at);
    if (end == std::string::npos) break;
    subjects.push_back(Trim(document.substr(at, end - at)));
  }
  return subjects;
}

void CheckIdentity(const SecurityFiles& files, const std::string& identity, const X509* cert) {
  const Certificate ca = ReadCertificate(files.identity_ca);
  CheckValidNow(ca.get(), files.identity_ca);
  CheckValidNow(cert, files.certificate);
  if (const std::string cn = CommonName(cert); cn != identity) {
    Fail(files.certificate, "subject CN '" + cn + "' does not match the process identity '" + identity + "'");
  }
  CheckSignedBy(const_cast<X509*>(cert), ca.get(), files.certificate, files.identity_ca);
  const Key key(PEM_read_bio_PrivateKey(Open(files.private_key).get(), nullptr, nullptr, nullptr));
  if (!key) Fail(files.private_key, "not a PEM private key");
  if (X509_check_private_key(cert, key.get()) != 1) Fail(files.private_key, "not the key of " + files.certificate);
}

void CheckPermissions(const SecurityFiles& files, const X509* cert) {
  const Certificate ca = ReadCertificate(files.permissions_ca);
  CheckValidNow(ca.get(), files.permissions_ca);
  SignedDocument(files.governance, ca.get(), files.permissions_ca);
  const std::string subject = Subject(cert);
  for (const auto& granted : GrantedSubjects(SignedDocument(files.permissions, ca.get(), files.permissions_ca))) {
    if (granted == subject) return;
  }
  Fail(files.permissions, "no grant for subject '" + subject + "' (the subject must be in RFC 2253 order)");
}

}  // namespace

void CheckSecurityFiles(const SecurityFiles& files, const std::string& identity) {
  const Certificate cert = ReadCertificate(files.certificate);
  CheckIdentity(files, identity, cert.get());
  CheckPermissions(files, cert.get());
}

}  // namespace mrslam::dds
