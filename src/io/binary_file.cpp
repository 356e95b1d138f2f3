#include "io/binary_file.hpp"

#include <algorithm>
#include <cerrno>

namespace eds {

InputError errorAt(const std::string& file, std::uint64_t offset, const std::string& what) {
  return InputError(file, "byte " + std::to_string(offset) + ": " + what);
}

FileFormat sniffFileFormat(const std::filesystem::path& file) {
  // Prophesee .raw files open with a text header whose lines start with "% ".
  static constexpr std::pair<std::string_view, FileFormat> kMagics[] = {
      {"#ROSBAG V2.0\n", FileFormat::kRosBag1},
      {std::string_view("SQLite format 3", 16), FileFormat::kSqlite},
      {"\x89MCAP0\r\n", FileFormat::kMcap},
      {"#!AER-DAT4.0\r\n", FileFormat::kAedat4},
      {std::string_view("\x89HDF\r\n\x1a\n", 8), FileFormat::kHdf5},
      {"% ", FileFormat::kPropheseeRaw}};
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (!f) return FileFormat::kUnknown;
  char head[16];
  const std::size_t n = std::fread(head, 1, sizeof head, f);
  std::fclose(f);
  for (const auto& [magic, format] : kMagics)
    if (std::string_view(head, n).starts_with(magic)) return format;
  return FileFormat::kUnknown;
}

BinaryFile::BinaryFile(const std::filesystem::path& path) : path_(path.string()) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path_, "file not found");
  file_ = std::fopen(path_.c_str(), "rb");
  if (!file_) throw InputError(path_, std::string("cannot open: ") + std::strerror(errno));
  size_ = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path_, "cannot read its size: " + ec.message());
}

BinaryFile::~BinaryFile() {
  if (file_) std::fclose(file_);
}

void BinaryFile::seek(std::uint64_t offset) {
  if (offset > size_) throw error("seek to byte " + std::to_string(offset) + " past the end of the file");
  if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) throw error("cannot seek");
  offset_ = offset;
}

std::size_t BinaryFile::readSome(void* dst, std::size_t n) {
  const std::size_t got = std::fread(dst, 1, n, file_);
  if (got < n && std::ferror(file_)) throw error(std::string("read failed: ") + std::strerror(errno));
  offset_ += got;
  return got;
}

void BinaryFile::requireLeft(std::size_t n, const char* what) const {
  if (n > size_ - std::min(offset_, size_))
    throw error(std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes, " +
                std::to_string(size_ - std::min(offset_, size_)) + " left in the file");
}

void BinaryFile::readExact(void* dst, std::size_t n, const char* what) {
  requireLeft(n, what);
  if (readSome(dst, n) != n) throw error(std::string("truncated: ") + what);
}

void BinaryFile::readExact(std::vector<std::uint8_t>& dst, std::size_t n, const char* what) {
  requireLeft(n, what);
  dst.resize(n);
  readExact(dst.data(), n, what);
}

bool BinaryFile::readLine(std::string& line, std::size_t max_length) {
  line.clear();
  if (atEnd()) return false;
  for (int c; (c = std::fgetc(file_)) != EOF;) {
    ++offset_;
    if (c == '\n') return true;
    if (line.size() >= max_length) throw error("line longer than " + std::to_string(max_length) + " bytes");
    line.push_back(static_cast<char>(c));
  }
  return true;
}

}  // namespace eds
