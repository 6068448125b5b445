// Binary state streams for checkpoints: the reader's checks and messages, and the FNV-1a hash.
#include "core/binary_io.hpp"

namespace mpsfsi {

std::uint64_t fnv1a64(const char* data, const std::size_t size, std::uint64_t hash) {
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 1099511628211ull;
  }
  return hash;
}

BinaryReader::BinaryReader(const std::string& data, std::string source, const std::size_t begin, const std::size_t end)
    : data_(data), source_(std::move(source)), pos_(begin), end_(end == std::string::npos ? data.size() : end) {
  if (end_ > data_.size() || pos_ > end_) throw std::logic_error("BinaryReader: range outside the data");
}

void BinaryReader::fail(const std::string& message) const { throw StateFormatError(source_ + ": " + message); }

void BinaryReader::need(const std::size_t n, const char* what) const {
  if (n > remaining())
    fail("truncated or damaged: " + std::string(what) + " needs " + std::to_string(n) + " bytes at offset " +
         std::to_string(pos_) + ", " + std::to_string(remaining()) + " left");
}

std::string BinaryReader::string(const char* what) {
  const std::uint64_t n = u64(what);
  need(n, what);
  std::string s = data_.substr(pos_, n);
  pos_ += n;
  return s;
}

void BinaryReader::expect_section(const std::string& name) {
  const std::string want = "[" + name + "]";
  // A marker is short: a long length means the reader is out of step with the writer.
  const std::size_t at = pos_;
  const std::uint64_t n = value<std::uint64_t>("a section marker");
  if (n > 256) fail("expected section '" + name + "' at offset " + std::to_string(at) + ", found other data");
  need(n, "a section marker");
  const std::string got = data_.substr(pos_, n);
  pos_ += n;
  if (got != want)
    fail("expected section '" + name + "' at offset " + std::to_string(at) + ", found '" + got +
         "' (written by another version of the program?)");
}

}  // namespace mpsfsi
