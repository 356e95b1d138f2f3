#include "io/decompress.hpp"

#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>

namespace eds {

namespace {
constexpr std::size_t kMaxDecompressedBytes = std::size_t{1} << 30;
}  // namespace

void lz4FrameDecompress(const std::uint8_t* in, std::size_t in_size, std::vector<std::uint8_t>& out,
                        const std::string& file, std::uint64_t offset) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
    throw errorAt(file, offset, "cannot create an lz4 context");
  std::size_t src_pos = 0, dst_pos = 0, ret = 1;
  while (src_pos < in_size && ret != 0) {
    std::size_t src_n = in_size - src_pos, dst_n = out.size() - dst_pos;
    ret = LZ4F_decompress(ctx, out.data() + dst_pos, &dst_n, in + src_pos, &src_n, nullptr);
    if (LZ4F_isError(ret)) {
      LZ4F_freeDecompressionContext(ctx);
      throw errorAt(file, offset, std::string("corrupt lz4 block: ") + LZ4F_getErrorName(ret));
    }
    src_pos += src_n;
    dst_pos += dst_n;
    if (src_n == 0 && dst_n == 0) break;  // no progress: output full or input exhausted
  }
  LZ4F_freeDecompressionContext(ctx);
  if (ret != 0 || dst_pos != out.size())
    throw errorAt(file, offset,
                  "lz4 block decompresses to " + std::to_string(dst_pos) + (ret != 0 ? "+" : "") +
                      " bytes, not the " + std::to_string(out.size()) + " its record says");
}

void zstdDecompress(const std::uint8_t* in, std::size_t in_size, std::vector<std::uint8_t>& out,
                    const std::string& file, std::uint64_t offset) {
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), in, in_size);
  if (ZSTD_isError(n))
    throw errorAt(file, offset, std::string("corrupt zstd block: ") + ZSTD_getErrorName(n));
  if (n != out.size())
    throw errorAt(file, offset,
                  "zstd block decompresses to " + std::to_string(n) + " bytes, not the " +
                      std::to_string(out.size()) + " its record says");
}

void lz4FrameDecompressAll(const std::uint8_t* in, std::size_t in_size, std::vector<std::uint8_t>& out,
                           const std::string& file, std::uint64_t offset) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
    throw errorAt(file, offset, "cannot create an lz4 context");
  out.resize(std::max<std::size_t>(4 * in_size, 1 << 12));
  std::size_t src_pos = 0, dst_pos = 0, ret = 1;
  while (ret != 0) {
    if (dst_pos == out.size()) {
      if (out.size() >= kMaxDecompressedBytes) break;
      out.resize(2 * out.size());
    }
    std::size_t src_n = in_size - src_pos, dst_n = out.size() - dst_pos;
    ret = LZ4F_decompress(ctx, out.data() + dst_pos, &dst_n, in + src_pos, &src_n, nullptr);
    if (LZ4F_isError(ret)) break;
    src_pos += src_n;
    dst_pos += dst_n;
    if (src_pos == in_size && dst_n == 0) break;  // input used up before the frame's end
  }
  LZ4F_freeDecompressionContext(ctx);
  if (LZ4F_isError(ret))
    throw errorAt(file, offset, std::string("corrupt lz4 block: ") + LZ4F_getErrorName(ret));
  if (ret != 0) throw errorAt(file, offset, "corrupt lz4 block: the frame ends early or is too large");
  out.resize(dst_pos);
}

void zstdDecompressAll(const std::uint8_t* in, std::size_t in_size, std::vector<std::uint8_t>& out,
                       const std::string& file, std::uint64_t offset) {
  const unsigned long long size = ZSTD_getFrameContentSize(in, in_size);
  if (size == ZSTD_CONTENTSIZE_ERROR) throw errorAt(file, offset, "corrupt zstd block: not a zstd frame");
  if (size != ZSTD_CONTENTSIZE_UNKNOWN) {
    if (size > kMaxDecompressedBytes) throw errorAt(file, offset, "zstd block too large");
    out.resize(static_cast<std::size_t>(size));
    zstdDecompress(in, in_size, out, file, offset);
    return;
  }
  ZSTD_DStream* ds = ZSTD_createDStream();
  ZSTD_inBuffer src{in, in_size, 0};
  out.resize(std::max<std::size_t>(4 * in_size, 1 << 12));
  ZSTD_outBuffer dst{out.data(), out.size(), 0};
  std::size_t ret = 1;
  while (ret != 0 && !ZSTD_isError(ret)) {
    if (dst.pos == dst.size) {
      if (out.size() >= kMaxDecompressedBytes) break;
      out.resize(2 * out.size());
      dst.dst = out.data();
      dst.size = out.size();
    }
    const std::size_t before = src.pos + dst.pos;
    ret = ZSTD_decompressStream(ds, &dst, &src);
    if (src.pos + dst.pos == before) break;
  }
  ZSTD_freeDStream(ds);
  if (ZSTD_isError(ret))
    throw errorAt(file, offset, std::string("corrupt zstd block: ") + ZSTD_getErrorName(ret));
  if (ret != 0) throw errorAt(file, offset, "corrupt zstd block: the frame ends early or is too large");
  out.resize(dst.pos);
}

}  // namespace eds
