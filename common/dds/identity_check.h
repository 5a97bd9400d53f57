#pragma once

#include <string>

#include "common/dds/security.h"

// Checks a process's DDS-Security files with OpenSSL before Fast DDS reads them: Fast DDS 2.9
// reports most mistakes only as "initialization error".
namespace mrslam::dds {

// Checks that every file is there and readable; that the certificate was signed by the identity
// CA, is valid now and names `identity` (its CN); that the private key is the certificate's; that
// the permissions CA signed the governance and the permissions; and that the permissions grant
// the certificate's subject. Throws DdsError with one line naming the file and the problem.
void CheckSecurityFiles(const SecurityFiles& files, const std::string& identity);

}  // namespace mrslam::dds
