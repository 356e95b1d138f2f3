#include <hdf5.h>

#include <algorithm>
#include <vector>

#include "core/error.hpp"
#include "io/hdf5_common.hpp"
#include "io/hdf5_events.hpp"

namespace eds {

using hdf5::failH5;
using hdf5::floorDiv;
using hdf5::Hid;
using hdf5::kBloscFilter;
using hdf5::QuietHdf5;

Hdf5Compression writeHdf5Events(const std::string& path, const EventArray& events, std::int64_t t_offset_us,
                                Hdf5Compression compression) {
  if (compression == Hdf5Compression::kBloscIfAvailable && !hdf5BloscAvailable()) {
    compression = Hdf5Compression::kGzip;
  }
  QuietHdf5 quiet;
  const std::size_t n = events.size();
  std::vector<std::int64_t> t_us(n);
  std::vector<std::uint8_t> p01(n);
  for (std::size_t i = 0; i < n; ++i) {
    t_us[i] = floorDiv(events.t[i], 1000) - t_offset_us;
    p01[i] = events.p[i] > 0 ? 1 : 0;
  }
  std::vector<std::uint64_t> ms_to_idx;
  if (n > 0) {
    const std::int64_t last_ms = std::max<std::int64_t>(t_us.back(), 0) / 1000;
    ms_to_idx.resize(static_cast<std::size_t>(last_ms) + 1);
    std::size_t idx = 0;
    for (std::size_t ms = 0; ms < ms_to_idx.size(); ++ms) {
      while (idx < n && t_us[idx] < static_cast<std::int64_t>(ms) * 1000) ++idx;
      ms_to_idx[ms] = idx;
    }
  }

  Hid file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
  if (!file.valid()) failH5(path, "cannot create the HDF5 file");
  Hid group(H5Gcreate2(file.get(), "events", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!group.valid()) failH5(path, "cannot create group events");

  auto write = [&](const char* name, hid_t ftype, hid_t mtype, const void* data, std::size_t len) {
    const hsize_t dims[1] = {len};
    Hid space(H5Screate_simple(1, dims, nullptr), H5Sclose);
    Hid dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    if (compression != Hdf5Compression::kNone) {
      const hsize_t chunk[1] = {std::clamp<hsize_t>(len, 1, hsize_t{1} << 16)};
      H5Pset_chunk(dcpl.get(), 1, chunk);
      if (compression == Hdf5Compression::kGzip) {
        H5Pset_shuffle(dcpl.get());  // groups the similar high bytes: much better ratios
        H5Pset_deflate(dcpl.get(), 1);
      } else {
        // Slots 0-3 are filled in by the filter; then level 5, byte shuffle, compressor lz4.
        const unsigned cd[7] = {0, 0, 0, 0, 5, 1, 1};
        H5Pset_filter(dcpl.get(), kBloscFilter, H5Z_FLAG_MANDATORY, 7, cd);
      }
    }
    Hid ds(H5Dcreate2(file.get(), name, ftype, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT), H5Dclose);
    if (!ds.valid() || (len > 0 && H5Dwrite(ds.get(), mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)) {
      failH5(path, std::string("cannot write ") + name);
    }
  };
  write("events/t", H5T_STD_I64LE, H5T_NATIVE_INT64, t_us.data(), n);
  write("events/x", H5T_STD_U16LE, H5T_NATIVE_UINT16, events.x.data(), n);
  write("events/y", H5T_STD_U16LE, H5T_NATIVE_UINT16, events.y.data(), n);
  write("events/p", H5T_STD_U8LE, H5T_NATIVE_UINT8, p01.data(), n);
  write("ms_to_idx", H5T_STD_U64LE, H5T_NATIVE_UINT64, ms_to_idx.data(), ms_to_idx.size());

  Hid scalar(H5Screate(H5S_SCALAR), H5Sclose);
  Hid ds(
      H5Dcreate2(file.get(), "t_offset", H5T_STD_I64LE, scalar.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      H5Dclose);
  if (!ds.valid() || H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &t_offset_us) < 0) {
    failH5(path, "cannot write t_offset");
  }
  ds.reset();
  if (H5Fflush(file.get(), H5F_SCOPE_LOCAL) < 0) failH5(path, "cannot flush");
  return compression;
}

}  // namespace eds
