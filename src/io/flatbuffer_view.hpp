#pragma once
// Reading FlatBuffers tables in place (AEDAT 4.0 packets), bounds-checked: a root offset, tables that
// point to their vtable, vectors and strings by 32-bit relative offsets. Only what the readers need.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "io/binary_file.hpp"

namespace eds {

class FlatTable {
 public:
  // The root table of a buffer (its first 4 bytes are the root's offset).
  static FlatTable root(const ByteView& buf) {
    ByteView v = buf;
    return FlatTable(buf, v.le<std::uint32_t>("flatbuffer root offset"));
  }

  // Field `index` (0-based, in schema order): its offset in the buffer, or 0 when absent.
  std::size_t fieldPos(int index) const {
    const std::size_t slot = 4 + 2 * static_cast<std::size_t>(index);
    if (slot + 2 > vtable_size_) return 0;
    ByteView v = buf_;
    v.seek(vtable_ + slot);
    const auto off = v.le<std::uint16_t>("flatbuffer vtable entry");
    return off == 0 ? 0 : pos_ + off;
  }
  template <typename T>
  T scalar(int index, T fallback) const {
    const std::size_t p = fieldPos(index);
    if (p == 0) return fallback;
    ByteView v = buf_;
    v.seek(p);
    return v.le<T>("flatbuffer field");
  }
  // A vector of `element_bytes`-sized elements: a view of its bytes and the element count.
  ByteView vector(int index, std::size_t element_bytes, std::size_t& count) const {
    const std::size_t p = fieldPos(index);
    count = 0;
    if (p == 0) return ByteView(nullptr, 0, nullptr, 0);
    ByteView v = buf_;
    v.seek(p);
    v.seek(p + v.le<std::uint32_t>("flatbuffer vector offset"));
    count = v.le<std::uint32_t>("flatbuffer vector length");
    if (element_bytes != 0 && count > v.remaining() / element_bytes)
      throw v.error(v.pos(),
                    "flatbuffer vector of " + std::to_string(count) + " elements runs past its buffer");
    return v.take(count * element_bytes, "flatbuffer vector");
  }
  std::string string(int index) const {
    std::size_t n = 0;
    const ByteView s = vector(index, 1, n);
    return n == 0 ? std::string() : std::string(reinterpret_cast<const char*>(s.data()), n);
  }
  // A vector of tables: each element is a 32-bit offset, from the element, to its table.
  std::vector<FlatTable> tables(int index) const {
    std::size_t n = 0;
    const ByteView v = vector(index, 4, n);
    std::vector<FlatTable> out;
    out.reserve(n);
    const auto first = static_cast<std::size_t>(v.data() - buf_.data());
    for (std::size_t i = 0; i < n; ++i) {
      std::uint32_t off;
      std::memcpy(&off, v.data() + 4 * i, 4);
      out.push_back(FlatTable(buf_, first + 4 * i + off));
    }
    return out;
  }
  FlatTable table(int index) const {
    const std::size_t p = fieldPos(index);
    if (p == 0) throw buf_.error(pos_, "flatbuffer table lacks field " + std::to_string(index));
    ByteView v = buf_;
    v.seek(p);
    return FlatTable(buf_, p + v.le<std::uint32_t>("flatbuffer table offset"));
  }

 private:
  FlatTable(const ByteView& buf, std::size_t pos) : buf_(buf), pos_(pos) {
    ByteView v = buf_;
    v.seek(pos_);
    const auto soffset = v.le<std::int32_t>("flatbuffer vtable offset");
    const auto vt = static_cast<std::int64_t>(pos_) - soffset;
    if (vt < 0 || static_cast<std::uint64_t>(vt) + 4 > buf_.size())
      throw buf_.error(pos_, "flatbuffer vtable outside its buffer");
    vtable_ = static_cast<std::size_t>(vt);
    v.seek(vtable_);
    vtable_size_ = v.le<std::uint16_t>("flatbuffer vtable size");
    if (vtable_ + vtable_size_ > buf_.size())
      throw buf_.error(vtable_, "flatbuffer vtable runs past its buffer");
  }

  ByteView buf_;
  std::size_t pos_ = 0, vtable_ = 0, vtable_size_ = 0;
};

}  // namespace eds
