#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

// A binary archive of an object's state, one function for both ways: a class lists its members
// once, in `void Io(common::Archive& ar) { ar(a_, b_, c_); }` (or a free `Io(Archive&, T&)` found
// by argument-dependent lookup), and the same call writes them (an archive for writing) or reads
// them back in place (an archive for reading). Trivially copyable values go as their bytes,
// Eigen matrices as their coefficients (dynamic ones after their size), containers as a count
// and their elements. Meant for the state of one process restored by the same build on the same
// machine (snapshot.h adds a header that says so): no byte-order or layout conversion. Reading
// never trusts a count: one that more bytes than remain could not hold is an ArchiveError, as is
// reading past the end. Pure; not thread-safe.
namespace mrslam::common {

class ArchiveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Archive {
 public:
  // An archive that writes into bytes().
  static Archive ForWriting() { return Archive(std::string(), false); }
  // An archive that reads the given bytes back.
  static Archive ForReading(std::string bytes) { return Archive(std::move(bytes), true); }

  bool loading() const { return loading_; }
  const std::string& bytes() const { return bytes_; }
  // Reading: whether every byte was read.
  bool AtEnd() const { return position_ == bytes_.size(); }

  // Writes or reads n raw bytes at data.
  void Raw(void* data, std::size_t n);
  // Writes n, or reads and returns a count, of elements of at least min_bytes bytes each.
  std::size_t Count(std::size_t n, std::size_t min_bytes);
  // Reading: an ArchiveError unless at least count elements of `bytes` bytes each remain.
  void Expect(std::size_t count, std::size_t bytes) const;

  // Writes or reads each value in turn.
  template <typename... T>
  void operator()(T&... values);

 private:
  Archive(std::string bytes, bool loading) : bytes_(std::move(bytes)), loading_(loading) {}

  std::string bytes_;
  std::size_t position_ = 0;
  bool loading_;
};

// Whether T has a member `void Io(Archive&)`.
template <typename T, typename = void>
struct HasIoMember : std::false_type {};
template <typename T>
struct HasIoMember<T, std::void_t<decltype(std::declval<T&>().Io(std::declval<Archive&>()))>> : std::true_type {};

template <typename T>
void Io(Archive& ar, T& value);
void Io(Archive& ar, std::string& value);
template <typename T, typename A>
void Io(Archive& ar, std::vector<T, A>& values);
template <typename T>
void Io(Archive& ar, std::deque<T>& values);
template <typename K, typename V, typename C>
void Io(Archive& ar, std::map<K, V, C>& values);
template <typename K, typename C>
void Io(Archive& ar, std::set<K, C>& values);
template <typename T>
void Io(Archive& ar, std::optional<T>& value);
template <typename A, typename B>
void Io(Archive& ar, std::pair<A, B>& value);
template <typename S, int R, int C, int O, int MR, int MC>
void Io(Archive& ar, Eigen::Matrix<S, R, C, O, MR, MC>& m);

template <typename... T>
void Archive::operator()(T&... values) {
  (Io(*this, values), ...);
}

template <typename T>
void Io(Archive& ar, T& value) {
  if constexpr (HasIoMember<T>::value) {
    value.Io(ar);
  } else {
    static_assert(std::is_trivially_copyable_v<T> && !std::is_pointer_v<T>,
                  "give the type an Io(Archive&) member or a free Io(Archive&, T&)");
    ar.Raw(&value, sizeof(T));
  }
}

inline void Io(Archive& ar, std::string& value) {
  const std::size_t n = ar.Count(value.size(), 1);
  if (ar.loading()) value.resize(n);
  ar.Raw(value.data(), n);
}

template <typename T, typename A>
void Io(Archive& ar, std::vector<T, A>& values) {
  static_assert(!std::is_same_v<T, bool>, "std::vector<bool> has no elements to refer to");
  const std::size_t n = ar.Count(values.size(), std::is_trivially_copyable_v<T> ? sizeof(T) : 1);
  if (ar.loading()) {
    values.clear();
    values.resize(n);
  }
  if constexpr (std::is_trivially_copyable_v<T> && !HasIoMember<T>::value) {
    ar.Raw(values.data(), n * sizeof(T));
  } else {
    for (auto& v : values) Io(ar, v);
  }
}

template <typename T>
void Io(Archive& ar, std::deque<T>& values) {
  const std::size_t n = ar.Count(values.size(), 1);
  if (ar.loading()) {
    values.clear();
    values.resize(n);
  }
  for (auto& v : values) Io(ar, v);
}

template <typename K, typename V, typename C>
void Io(Archive& ar, std::map<K, V, C>& values) {
  const std::size_t n = ar.Count(values.size(), 1);
  if (!ar.loading()) {
    for (auto& [key, value] : values) {
      K k = key;
      ar(k, value);
    }
    return;
  }
  values.clear();
  for (std::size_t i = 0; i < n; ++i) {
    K k{};
    V v{};
    ar(k, v);
    values.emplace_hint(values.end(), std::move(k), std::move(v));
  }
}

template <typename K, typename C>
void Io(Archive& ar, std::set<K, C>& values) {
  const std::size_t n = ar.Count(values.size(), 1);
  if (!ar.loading()) {
    for (K k : values) ar(k);
    return;
  }
  values.clear();
  for (std::size_t i = 0; i < n; ++i) {
    K k{};
    ar(k);
    values.insert(values.end(), std::move(k));
  }
}

template <typename T>
void Io(Archive& ar, std::optional<T>& value) {
  bool has = value.has_value();
  ar(has);
  if (!has) {
    value.reset();
    return;
  }
  if (ar.loading()) value.emplace();
  Io(ar, *value);
}

template <typename A, typename B>
void Io(Archive& ar, std::pair<A, B>& value) {
  ar(value.first, value.second);
}

template <typename S, int R, int C, int O, int MR, int MC>
void Io(Archive& ar, Eigen::Matrix<S, R, C, O, MR, MC>& m) {
  static_assert(std::is_trivially_copyable_v<S>);
  if constexpr (R == Eigen::Dynamic || C == Eigen::Dynamic) {
    auto rows = static_cast<std::int64_t>(m.rows());
    auto cols = static_cast<std::int64_t>(m.cols());
    ar(rows, cols);
    if (ar.loading()) {
      if (rows < 0 || cols < 0 || (R != Eigen::Dynamic && rows != R) || (C != Eigen::Dynamic && cols != C)) {
        throw ArchiveError("archive: a matrix of impossible size");
      }
      ar.Expect(static_cast<std::size_t>(rows), static_cast<std::size_t>(cols) * sizeof(S));
      m.resize(rows, cols);
    }
  }
  ar.Raw(m.data(), static_cast<std::size_t>(m.size()) * sizeof(S));
}

}  // namespace mrslam::common
