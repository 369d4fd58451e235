// Internal to mapio: the body's writer and reader over cereal's portable binary archives
// (little-endian on disk whatever the host, cereal swaps bytes where needed). Everything in the
// body is a fixed-size scalar or a length-prefixed array of scalars (docs/MAP_FORMAT.md), written
// in one call each so that loading a map is a few large copies rather than millions of small
// reads. The reader checks every length against the bytes that are left before allocating, and
// turns every failure into an InputError naming the file, the byte offset and the record.
#pragma once

#include <cstdint>
#include <memory>
#include <sstream>
#include <streambuf>
#include <string>
#include <type_traits>
#include <vector>

#include <cereal/archives/portable_binary.hpp>

#include "moslam/util/error.h"

namespace moslam::mapio::internal {

class Writer {
 public:
  Writer() : archive_(stream_) {}
  template <typename T>
  void Value(const T& v) {
    static_assert(std::is_arithmetic_v<T>);
    archive_(v);
  }
  template <typename T>
  void Array(const T* data, size_t n) {
    static_assert(std::is_arithmetic_v<T>);
    Value(static_cast<uint64_t>(n));
    if (n > 0) archive_(cereal::binary_data(data, n * sizeof(T)));
  }
  template <typename T>
  void Vector(const std::vector<T>& v) {
    Array(v.data(), v.size());
  }
  std::string Bytes() const { return stream_.str(); }

 private:
  std::ostringstream stream_;
  cereal::PortableBinaryOutputArchive archive_;
};

// A read-only stream buffer over bytes owned elsewhere (no copy of a large body).
class MemoryBuffer : public std::streambuf {
 public:
  MemoryBuffer(const char* data, size_t size) {
    char* p = const_cast<char*>(data);  // never written: the buffer is only read
    setg(p, p, p + size);
  }
  size_t offset() const { return static_cast<size_t>(gptr() - eback()); }
  size_t left() const { return static_cast<size_t>(egptr() - gptr()); }
};

class Reader {
 public:
  // `base_offset`: the body's offset in the file, so that errors give file offsets.
  Reader(const std::string& path, const char* data, size_t size, size_t base_offset)
      : path_(path),
        base_(base_offset),
        buffer_(data, size),
        stream_(&buffer_),
        archive_(stream_) {}

  // What is being read, for error messages ("keyframe 12", "map point 3051").
  void SetRecord(std::string record) { record_ = std::move(record); }

  template <typename T>
  T Value() {
    static_assert(std::is_arithmetic_v<T>);
    T v{};
    try {
      archive_(v);
    } catch (const cereal::Exception&) {
      Fail("truncated");
    }
    return v;
  }
  template <typename T>
  std::vector<T> Vector() {
    static_assert(std::is_arithmetic_v<T>);
    const auto n = Value<uint64_t>();
    if (n > buffer_.left() / sizeof(T)) {
      Fail("an array of " + std::to_string(n) + " elements longer than the " +
           std::to_string(buffer_.left()) + " bytes left");
    }
    std::vector<T> v(static_cast<size_t>(n));
    if (n > 0) {
      try {
        archive_(cereal::binary_data(v.data(), v.size() * sizeof(T)));
      } catch (const cereal::Exception&) {
        Fail("truncated");
      }
    }
    return v;
  }
  size_t left() const { return buffer_.left(); }
  size_t offset() const { return base_ + buffer_.offset(); }

  // InputError: "<path>: <what> at byte <offset> (<record>)".
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path_ + ": " + what + " at byte " + std::to_string(offset()) +
                     (record_.empty() ? "" : " (" + record_ + ")"));
  }

 private:
  std::string path_;
  size_t base_;
  std::string record_;
  MemoryBuffer buffer_;
  std::istream stream_;
  cereal::PortableBinaryInputArchive archive_;
};

}  // namespace moslam::mapio::internal
