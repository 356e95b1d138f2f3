#pragma once
// Reads a text file (plain or gzip, by magic bytes) in large blocks and hands out whole lines with
// their 1-based numbers. One class for every text format, so each reader only parses fields.
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace eds {

class LineReader {
 public:
  // Throws InputError if the file is missing or unreadable.
  explicit LineReader(const std::filesystem::path& file, std::size_t block_bytes = 1 << 20);
  ~LineReader();
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  // Next line without its '\n' (a trailing '\r' is kept: the field parsers treat it as space).
  // Returns false at the end of the file. The view is valid until the next call.
  bool next(std::string_view& line);
  std::size_t lineNumber() const { return line_no_; }

  // Bulk access for hot parsers: a view of whole lines (ending in '\n', or the file's unterminated
  // last line) without copying; empty at the end of the file. After parsing a prefix, the caller
  // calls consume() with the bytes and lines it used.
  std::string_view available();
  void consume(std::size_t bytes, std::size_t lines) {
    begin_ += bytes;
    line_no_ += lines;
  }
  const std::string& fileName() const { return name_; }
  bool compressed() const { return gz_ != nullptr; }

 private:
  bool refill();  // moves the unread tail to the front and reads more; false at end of file

  std::string name_;
  std::FILE* file_ = nullptr;
  void* gz_ = nullptr;  // gzFile; kept opaque so zlib.h stays out of the header
  std::vector<char> buf_;
  std::size_t begin_ = 0, end_ = 0;
  bool eof_ = false;
  std::size_t line_no_ = 0;
};

}  // namespace eds
