#include "io/hdf5_common.hpp"

#include <dlfcn.h>

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

}  // namespace eds::hdf5
