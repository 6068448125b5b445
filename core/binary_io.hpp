// Binary state streams for checkpoints: BinaryWriter appends fixed-size values, strings and arrays to a
// byte buffer in the machine's byte order; BinaryReader reads them back and throws StateFormatError,
// saying what it was reading, when the data end early or do not match what the reader expects. Named
// sections (section() / expect_section()) make a reader that gets out of step fail at once with a clear
// message instead of reading garbage. Every module serialises its own state with these (core, fluid,
// solid and coupling each know only their own part).
#pragma once

#include "core/types.hpp"

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace mpsfsi {

/// State data that cannot be read: truncated, damaged, or written for other data (the message says which).
class StateFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// 64-bit FNV-1a hash of bytes (checksums of checkpoint files and of output-file prefixes).
std::uint64_t fnv1a64(const char* data, std::size_t size, std::uint64_t hash = 14695981039346656037ull);

/// Element types stored as raw bytes: trivially copyable ones and Vec (two doubles, no padding).
template <class T>
inline constexpr bool is_raw_element = std::is_trivially_copyable_v<T> || std::is_same_v<T, Vec>;
static_assert(sizeof(Vec) == dim * sizeof(Real), "Vec must be dim packed Reals");

class BinaryWriter {
 public:
  template <class T>
  void value(const T& v) {
    static_assert(is_raw_element<T>, "BinaryWriter::value needs a trivially copyable type");
    const auto* b = reinterpret_cast<const char*>(&v);
    buf_.append(b, sizeof(T));
  }
  void u64(const std::uint64_t v) { value(v); }
  void i64(const std::int64_t v) { value(v); }
  void f64(const double v) { value(v); }
  void boolean(const bool v) { value(static_cast<std::uint8_t>(v ? 1 : 0)); }
  void string(const std::string& s) {
    u64(s.size());
    buf_.append(s);
  }
  /// An array: its element size, its length, then the elements.
  template <class T>
  void array(const std::vector<T>& a) {
    static_assert(is_raw_element<T>, "BinaryWriter::array needs a trivially copyable element type");
    u64(sizeof(T));
    u64(a.size());
    if (!a.empty()) buf_.append(reinterpret_cast<const char*>(a.data()), a.size() * sizeof(T));
  }
  /// A section marker; the reader's expect_section() with the same name must meet it.
  void section(const std::string& name) { string("[" + name + "]"); }

  const std::string& bytes() const { return buf_; }
  std::string& bytes() { return buf_; }

 private:
  std::string buf_;
};

class BinaryReader {
 public:
  /// Reads from data[begin, end); `source` names the data in messages (e.g. the checkpoint file).
  BinaryReader(const std::string& data, std::string source, std::size_t begin = 0, std::size_t end = std::string::npos);

  template <class T>
  T value(const char* what) {
    static_assert(is_raw_element<T>, "BinaryReader::value needs a trivially copyable type");
    need(sizeof(T), what);
    T v;
    std::memcpy(static_cast<void*>(&v), data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::uint64_t u64(const char* what) { return value<std::uint64_t>(what); }
  std::int64_t i64(const char* what) { return value<std::int64_t>(what); }
  double f64(const char* what) { return value<double>(what); }
  bool boolean(const char* what) { return value<std::uint8_t>(what) != 0; }
  std::string string(const char* what);
  /// An array written by BinaryWriter::array; throws when its element size differs from sizeof(T) or,
  /// with expected_size given, when its length differs.
  template <class T>
  std::vector<T> array(const char* what, const std::size_t expected_size = npos) {
    static_assert(is_raw_element<T>, "BinaryReader::array needs a trivially copyable element type");
    std::vector<T> a;
    read_array_header(what, sizeof(T), expected_size, a);
    return a;
  }
  /// Reads the next section marker and throws unless it is `name`.
  void expect_section(const std::string& name);

  std::size_t position() const { return pos_; }
  std::size_t remaining() const { return end_ - pos_; }
  bool at_end() const { return pos_ == end_; }
  const std::string& source() const { return source_; }
  /// Throws StateFormatError("<source>: <message>").
  [[noreturn]] void fail(const std::string& message) const;

  static constexpr std::size_t npos = static_cast<std::size_t>(-1);

 private:
  void need(std::size_t n, const char* what) const;
  template <class T>
  void read_array_header(const char* what, const std::size_t elem, const std::size_t expected, std::vector<T>& a) {
    const std::uint64_t es = u64(what);
    if (es != elem)
      fail(std::string(what) + ": element size " + std::to_string(es) + " bytes, expected " + std::to_string(elem));
    const std::uint64_t n = u64(what);
    if (expected != npos && n != expected)
      fail(std::string(what) + ": " + std::to_string(n) + " entries, expected " + std::to_string(expected));
    if (n > remaining() / (elem ? elem : 1)) need(n * elem, what);
    a.resize(n);
    if (n) std::memcpy(static_cast<void*>(a.data()), data_.data() + pos_, n * elem);
    pos_ += n * elem;
  }

  const std::string& data_;
  std::string source_;
  std::size_t pos_ = 0, end_ = 0;
};

}  // namespace mpsfsi
