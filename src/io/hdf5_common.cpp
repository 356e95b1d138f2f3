#include "io/hdf5_common.hpp"

#include <dlfcn.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "core/error.hpp"

namespace eds::hdf5 {

namespace fs = std::filesystem;

// The outermost and innermost messages of HDF5's error stack: what failed and why.
std::string lastHdf5Error() {
  std::pair<std::string, std::string> msgs;
  auto collect = [](unsigned n, const H5E_error2_t* err, void* data) -> herr_t {
    auto* m = static_cast<std::pair<std::string, std::string>*>(data);
    if (err->desc == nullptr) return 0;
    if (n == 0) m->first = err->desc;
    m->second = err->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect, &msgs);
  H5Eclear2(H5E_DEFAULT);
  if (msgs.first.empty()) return "";
  if (msgs.first == msgs.second) return " (HDF5: " + msgs.first + ")";
  return " (HDF5: " + msgs.first + ": " + msgs.second + ")";
}

void failH5(const std::string& file, const std::string& what) {
  throw InputError(file, what + lastHdf5Error());
}

std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
  return a / b - ((a % b != 0) && ((a < 0) != (b < 0)));
}

// Debian installs filter plugins next to the HDF5 library (<libdir>/hdf5/serial/plugins). Its own
// HDF5 searches there by default, but an HDF5 built elsewhere (static, self-built) does not; adding
// the directory lets blosc files open without HDF5_PLUGIN_PATH either way.
void addPluginPath() {
  if (std::getenv("HDF5_PLUGIN_PATH") != nullptr) return;  // the user's setting wins
  std::vector<fs::path> candidates;
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&H5open), &info) != 0 && info.dli_fname != nullptr) {
    candidates.push_back(fs::path(info.dli_fname).parent_path() / "hdf5/serial/plugins");
  }
  std::error_code ec;
  // Fallback for a statically linked HDF5: the multiarch directories.
  for (const auto& entry : fs::directory_iterator("/usr/lib", ec)) {
    if (entry.path().filename().string().ends_with("-linux-gnu")) {
      candidates.push_back(entry.path() / "hdf5/serial/plugins");
    }
  }
  unsigned count = 0;
  if (H5PLsize(&count) < 0) return;
  std::vector<std::string> present;
  for (unsigned i = 0; i < count; ++i) {
    std::array<char, 4096> buf{};
    if (H5PLget(i, buf.data(), buf.size()) > 0) present.emplace_back(buf.data());
  }
  for (const auto& dir : candidates) {
    if (!fs::is_directory(dir, ec)) continue;
    const std::string canonical = fs::canonical(dir, ec).string();
    if (ec || std::find(present.begin(), present.end(), canonical) != present.end()) continue;
    if (H5PLappend(canonical.c_str()) >= 0) present.push_back(canonical);
  }
}

// Loads the blosc filter if needed. Blosc keeps a global context that only blosc_destroy() frees,
// which the plugin never calls; when HDF5 unloads the plugin at exit, that memory becomes
// unreachable and LeakSanitizer fails the program. Pinning the loaded libraries keeps it reachable.
bool loadBlosc() {
  addPluginPath();
  if (H5Zfilter_avail(kBloscFilter) <= 0) return false;
  for (const char* soname : {"libH5Zblosc.so", "libblosc.so.1"}) {
    if (void* handle = dlopen(soname, RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE)) dlclose(handle);
  }
  return true;
}

namespace {

// H5Z filter function: decompresses one chunk (flags has H5Z_FLAG_REVERSE) or compresses it (level
// cd_values[0], else 3). Returns the new size, 0 on failure (HDF5 then reports the read or write).
// A frame whose header does not give its size (a streaming compressor wrote it), decoded as a stream.
std::size_t zstdStreamed(std::size_t nbytes, std::size_t* buf_size, void** buf) {
  std::vector<char> out(std::max<std::size_t>(4 * nbytes, 1 << 16));
  ZSTD_DStream* ds = ZSTD_createDStream();
  ZSTD_inBuffer in{*buf, nbytes, 0};
  ZSTD_outBuffer o{out.data(), out.size(), 0};
  std::size_t rc = 0;
  while ((rc = ZSTD_decompressStream(ds, &o, &in)) != 0 && !ZSTD_isError(rc)) {
    if (o.pos < o.size) break;  // input used up with the frame unfinished: truncated
    out.resize(2 * out.size());
    o = {out.data(), out.size(), o.pos};
  }
  ZSTD_freeDStream(ds);
  void* result = rc == 0 ? H5allocate_memory(std::max<std::size_t>(o.pos, 1), false) : nullptr;
  if (result == nullptr) return 0;
  std::copy_n(out.data(), o.pos, static_cast<char*>(result));
  H5free_memory(*buf);
  *buf = result;
  *buf_size = std::max<std::size_t>(o.pos, 1);
  return o.pos;
}

std::size_t zstdFilter(unsigned flags, std::size_t cd_nelmts, const unsigned cd_values[], std::size_t nbytes,
                       std::size_t* buf_size, void** buf) {
  const bool decompress = (flags & H5Z_FLAG_REVERSE) != 0;
  const unsigned long long frame = decompress ? ZSTD_getFrameContentSize(*buf, nbytes) : 0;
  if (decompress && frame == ZSTD_CONTENTSIZE_UNKNOWN) return zstdStreamed(nbytes, buf_size, buf);
  if (decompress && frame == ZSTD_CONTENTSIZE_ERROR) return 0;
  const std::size_t capacity = decompress ? static_cast<std::size_t>(frame) : ZSTD_compressBound(nbytes);
  void* out = H5allocate_memory(std::max<std::size_t>(capacity, 1), false);
  if (out == nullptr) return 0;
  const std::size_t n = decompress ? ZSTD_decompress(out, capacity, *buf, nbytes)
                                   : ZSTD_compress(out, capacity, *buf, nbytes,
                                                   cd_nelmts > 0 ? static_cast<int>(cd_values[0]) : 3);
  if (ZSTD_isError(n) || (decompress && n != capacity)) {
    H5free_memory(out);
    return 0;
  }
  H5free_memory(*buf);
  *buf = out;
  *buf_size = capacity;
  return n;
}

}  // namespace

void registerZstdFilter() {
  addPluginPath();
  if (H5Zfilter_avail(kZstdFilter) > 0) return;
  static const H5Z_class2_t kClass = {H5Z_CLASS_T_VERS, kZstdFilter, 1,       1,
                                      "zstd (eds)",     nullptr,     nullptr, &zstdFilter};
  H5Zregister(&kClass);
}

}  // namespace eds::hdf5
