#include "io/line_reader.hpp"

#include <zlib.h>

#include <cstring>

#include "core/error.hpp"

namespace eds {

LineReader::LineReader(const std::filesystem::path& file, std::size_t block_bytes)
    : name_(file.string()), buf_(block_bytes) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw InputError(name_, "file not found");
  if (std::filesystem::is_directory(file, ec)) throw InputError(name_, "is a directory, not a file");
  file_ = std::fopen(name_.c_str(), "rb");
  if (!file_) throw InputError(name_, std::string("cannot open: ") + std::strerror(errno));
  unsigned char magic[2] = {0, 0};
  const std::size_t got = std::fread(magic, 1, 2, file_);
  if (got == 2 && magic[0] == 0x1f && magic[1] == 0x8b) {
    std::fclose(file_);
    file_ = nullptr;
    gzFile gz = gzopen(name_.c_str(), "rb");
    if (!gz) throw InputError(name_, "cannot open gzip file");
    gzbuffer(gz, 1 << 18);
    gz_ = gz;
  } else {
    std::rewind(file_);
  }
}

LineReader::~LineReader() {
  if (file_) std::fclose(file_);
  if (gz_) gzclose(static_cast<gzFile>(gz_));
}

bool LineReader::refill() {
  if (eof_) return false;
  const std::size_t tail = end_ - begin_;
  if (tail > 0 && begin_ > 0) std::memmove(buf_.data(), buf_.data() + begin_, tail);
  begin_ = 0;
  end_ = tail;
  if (end_ == buf_.size()) buf_.resize(buf_.size() * 2);  // a line longer than the block
  const std::size_t want = buf_.size() - end_;
  std::size_t got = 0;
  if (gz_) {
    const int n = gzread(static_cast<gzFile>(gz_), buf_.data() + end_, static_cast<unsigned>(want));
    if (n < 0) {
      int errnum = 0;
      const char* msg = gzerror(static_cast<gzFile>(gz_), &errnum);
      throw InputError(name_, line_no_ + 1, std::string("gzip read error: ") + msg);
    }
    got = static_cast<std::size_t>(n);
    // A truncated gzip stream reads as a short final block; zlib flags it as Z_BUF_ERROR.
    if (got == 0) {
      int errnum = 0;
      gzerror(static_cast<gzFile>(gz_), &errnum);
      if (errnum == Z_BUF_ERROR) throw InputError(name_, line_no_ + 1, "gzip stream is truncated");
    }
  } else {
    got = std::fread(buf_.data() + end_, 1, want, file_);
    if (got < want && std::ferror(file_)) throw InputError(name_, line_no_ + 1, "read error");
  }
  if (got == 0) eof_ = true;
  end_ += got;
  return got > 0;
}

std::string_view LineReader::available() {
  for (;;) {
    const char* start = buf_.data() + begin_;
    const std::size_t avail = end_ - begin_;
    // Last '\n' in the buffer: everything before it is whole lines.
    std::size_t last = avail;
    while (last > 0 && start[last - 1] != '\n') --last;
    if (last > 0) return {start, last};
    if (!refill()) return {start, end_ - begin_};  // unterminated last line, or empty at the end
  }
}

bool LineReader::next(std::string_view& line) {
  for (;;) {
    const char* start = buf_.data() + begin_;
    const std::size_t avail = end_ - begin_;
    const void* nl = avail ? std::memchr(start, '\n', avail) : nullptr;
    if (nl) {
      const std::size_t len = static_cast<const char*>(nl) - start;
      line = std::string_view(start, len);
      begin_ += len + 1;
      ++line_no_;
      return true;
    }
    if (!refill()) {
      if (end_ > begin_) {  // last line without '\n'
        line = std::string_view(buf_.data() + begin_, end_ - begin_);
        begin_ = end_;
        ++line_no_;
        return true;
      }
      return false;
    }
  }
}

}  // namespace eds
