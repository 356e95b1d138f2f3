#pragma once
// Internal helpers shared by the HDF5 event reader and writer (not part of the public API).
#include <hdf5.h>

#include <cstdint>
#include <string>
#include <utility>

namespace eds::hdf5 {

// Owns an HDF5 identifier and closes it with the matching H5?close.
class Hid {
 public:
  Hid() = default;
  Hid(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Hid(Hid&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), close_(o.close_) {}
  Hid& operator=(Hid&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, H5I_INVALID_HID);
      close_ = o.close_;
    }
    return *this;
  }
  ~Hid() { reset(); }
  void reset() {
    if (id_ >= 0 && close_ != nullptr) close_(id_);
    id_ = H5I_INVALID_HID;
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

// HDF5 prints its error stack to stderr by default; eds reports InputError instead. The previous
// handler is restored so that an application using HDF5 elsewhere keeps its own setting.
class QuietHdf5 {
 public:
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

// The outermost and innermost messages of HDF5's error stack: what failed and why.
std::string lastHdf5Error();

constexpr H5Z_filter_t kBloscFilter = 32001;  // ids registered with The HDF Group
constexpr H5Z_filter_t kZstdFilter = 32015;

[[noreturn]] void failH5(const std::string& file, const std::string& what);

std::int64_t floorDiv(std::int64_t a, std::int64_t b);

// Adds Debian's filter plugin folder to HDF5's search path unless HDF5_PLUGIN_PATH is set.
void addPluginPath();
// Makes the Zstandard filter (VECtor's files use it) available: Debian packages no HDF5 plugin for
// it, so eds registers its own, on libzstd, unless a plugin already provides it.
void registerZstdFilter();
// Loads the blosc filter (adding Debian's plugin folder to HDF5's search path if needed).
bool loadBlosc();

}  // namespace eds::hdf5
