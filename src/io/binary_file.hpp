#pragma once
// Reading binary recordings (Prophesee .raw, AEDAT 4.0, bags) without loading them whole: a file read
// through a buffer, whose errors name the file and the byte offset where the problem lies.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/error.hpp"

namespace eds {

// An InputError at a byte offset of a file: "FILE: byte N: what".
InputError errorAt(const std::string& file, std::uint64_t offset, const std::string& what);

// The file formats eds tells apart by their first bytes, whatever the file is called.
enum class FileFormat { kUnknown, kRosBag1, kSqlite, kMcap, kAedat4, kHdf5, kPropheseeRaw };

// The format of a file by its magic bytes; kUnknown for a missing file or one of no format listed.
FileFormat sniffFileFormat(const std::filesystem::path& file);

class BinaryFile {
 public:
  // InputError naming the file if it cannot be opened.
  explicit BinaryFile(const std::filesystem::path& path);
  ~BinaryFile();
  BinaryFile(const BinaryFile&) = delete;
  BinaryFile& operator=(const BinaryFile&) = delete;

  const std::string& path() const { return path_; }
  std::uint64_t size() const { return size_; }
  std::uint64_t offset() const { return offset_; }
  bool atEnd() const { return offset_ >= size_; }

  void seek(std::uint64_t offset);
  // Reads up to n bytes; returns how many (fewer only at the end of the file).
  std::size_t readSome(void* dst, std::size_t n);
  // Reads exactly n bytes; InputError "truncated" naming `what` when the file ends first.
  void readExact(void* dst, std::size_t n, const char* what);
  void readExact(std::vector<std::uint8_t>& dst, std::size_t n, const char* what);
  // Reads a little-endian integer.
  template <typename T>
  T readLe(const char* what) {
    static_assert(std::is_integral_v<T>);
    T v;
    readExact(&v, sizeof(T), what);
    return v;  // eds builds for little-endian hosts only (checked in CMake)
  }
  // Reads one line of text (without its '\n'); false at the end of the file.
  bool readLine(std::string& line, std::size_t max_length = 1 << 16);
  InputError error(const std::string& what) const { return errorAt(path_, offset_, what); }

 private:
  // Throws "truncated" naming `what` when fewer than n bytes are left.
  void requireLeft(std::size_t n, const char* what) const;

  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0;
  std::uint64_t offset_ = 0;
};

// A bounds-checked little-endian view of bytes held in memory (a decompressed chunk, a message).
// Errors name the file and the absolute offset of the byte that could not be read.
class ByteView {
 public:
  ByteView(const std::uint8_t* data, std::size_t size, const std::string* file, std::uint64_t base)
      : data_(data), size_(size), file_(file), base_(base) {}

  std::size_t size() const { return size_; }
  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return size_ - pos_; }
  const std::uint8_t* data() const { return data_; }
  const std::uint8_t* cursor() const { return data_ + pos_; }
  std::uint64_t absolute(std::size_t pos) const { return base_ + pos; }

  void seek(std::size_t pos) {
    if (pos > size_) throw error(pos, "offset past the end of its block");
    pos_ = pos;
  }
  void skip(std::size_t n) {
    need(n, "skipped bytes");
    pos_ += n;
  }
  void need(std::size_t n, const char* what) const {
    if (n > size_ - pos_) throw error(pos_, std::string(what) + ": length past the end of its block");
  }
  template <typename T>
  T le(const char* what) {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T), what);
    T v;
    std::memcpy(&v, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  // A sub-view of the next n bytes (and skips them).
  ByteView take(std::size_t n, const char* what) {
    need(n, what);
    ByteView v(data_ + pos_, n, file_, base_ + pos_);
    pos_ += n;
    return v;
  }
  InputError error(std::size_t pos, const std::string& what) const {
    return errorAt(file_ ? *file_ : std::string("<memory>"), base_ + pos, what);
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  const std::string* file_;
  std::uint64_t base_;
  std::size_t pos_ = 0;
};

}  // namespace eds
