#include "io/hdf5_layouts.hpp"

#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "io/hdf5_common.hpp"

namespace eds {

using hdf5::Hid;

namespace {

constexpr hsize_t kBlockRows = 1 << 16;

Hid openFile(const std::string& path) {
  hdf5::QuietHdf5 quiet;
  hdf5::registerZstdFilter();  // frames and events may be zstd-compressed
  Hid f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!f.valid()) hdf5::failH5(path, "cannot open as HDF5");
  return f;
}

// Opens a dataset and returns its dimensions; InputError when it is missing or has another rank.
Hid openArray(hid_t file, const std::string& path, const std::string& name, int rank, hsize_t* dims) {
  if (H5Lexists(file, name.substr(0, name.rfind('/')).c_str(), H5P_DEFAULT) <= 0 ||
      H5Lexists(file, name.c_str(), H5P_DEFAULT) <= 0)
    throw InputError(path, "missing dataset " + name);
  Hid ds(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) hdf5::failH5(path, name + " is not a dataset");
  Hid space(H5Dget_space(ds.get()), H5Sclose);
  if (H5Sget_simple_extent_ndims(space.get()) != rank)
    throw InputError(path, name + " is not a " + std::to_string(rank) + "-D array");
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  return ds;
}

// Reads rows [row, row + count) of a 2-D or 3-D dataset into `out` as `mem_type`.
void readRows(hid_t ds, const std::string& path, const std::string& name, int rank, const hsize_t* dims,
              hsize_t row, hsize_t count, hid_t mem_type, void* out) {
  hsize_t start[4] = {row, 0, 0, 0};
  hsize_t extent[4] = {count, rank > 1 ? dims[1] : 1, rank > 2 ? dims[2] : 1, rank > 3 ? dims[3] : 1};
  Hid file_space(H5Dget_space(ds), H5Sclose);
  H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, extent, nullptr);
  Hid mem_space(H5Screate_simple(rank, extent, nullptr), H5Sclose);
  if (H5Dread(ds, mem_type, mem_space.get(), file_space.get(), H5P_DEFAULT, out) < 0)
    hdf5::failH5(path,
                 "cannot read " + name + " rows " + std::to_string(row) + ".." + std::to_string(row + count));
}

}  // namespace

Hdf5Layout detectHdf5Layout(const std::filesystem::path& file) {
  hdf5::QuietHdf5 quiet;
  Hid f(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!f.valid()) return Hdf5Layout::kNone;
  const auto has = [&](std::initializer_list<const char*> chain) {
    for (const char* g : chain)
      if (H5Lexists(f.get(), g, H5P_DEFAULT) <= 0) return false;
    return true;
  };
  if (H5Aexists(f.get(), "eds_layout") > 0) return Hdf5Layout::kEds;
  if (has({"davis", "davis/left", "davis/left/events"})) return Hdf5Layout::kMvsec;
  if (has({"prophesee", "prophesee/left", "prophesee/left/t"})) return Hdf5Layout::kM3ed;
  if (has({"events", "events/t"})) return Hdf5Layout::kDsec;
  return Hdf5Layout::kNone;
}

Hdf5FrameDatasets frameDatasets(Hdf5Layout layout) {
  if (layout == Hdf5Layout::kMvsec) return {"davis/left/image_raw", "davis/left/image_raw_ts", 0};
  if (layout == Hdf5Layout::kM3ed) return {"ovc/left/data", "ovc/ts", 1000};
  if (layout == Hdf5Layout::kEds) return {"frames/images", "frames/t", 1};
  return {};
}

namespace {

// A frame stack is N x H x W, or N x H x W x 1.
Hid openFrames(hid_t file, const std::string& path, const std::string& name, hsize_t* dims) {
  Hid ds = H5Lexists(file, name.substr(0, name.find('/')).c_str(), H5P_DEFAULT) > 0 &&
                   H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0
               ? Hid(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose)
               : Hid();
  if (!ds.valid()) throw InputError(path, "missing dataset " + name);
  Hid space(H5Dget_space(ds.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  dims[3] = 1;
  if (rank < 3 || rank > 4) throw InputError(path, name + " is not an N x H x W (x 1) image stack");
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  if (dims[3] != 1) throw InputError(path, name + " has " + std::to_string(dims[3]) + " channels, not 1");
  return ds;
}

}  // namespace

Hdf5FrameIndex readHdf5FrameIndex(const std::filesystem::path& file, const Hdf5FrameDatasets& where) {
  const std::string path = file.string();
  Hid f = openFile(path);
  Hdf5FrameIndex frames;
  if (where.images.empty() ||
      H5Lexists(f.get(), where.images.substr(0, where.images.find('/')).c_str(), H5P_DEFAULT) <= 0 ||
      H5Lexists(f.get(), where.images.c_str(), H5P_DEFAULT) <= 0)
    return frames;
  hsize_t dims[4] = {}, ts_dims[1] = {};
  Hid images = openFrames(f.get(), path, where.images, dims);
  Hid ts = openArray(f.get(), path, where.times, 1, ts_dims);
  if (ts_dims[0] != dims[0])
    throw InputError(path, where.times + " has " + std::to_string(ts_dims[0]) + " times for " +
                               std::to_string(dims[0]) + " images");
  std::vector<double> seconds(ts_dims[0]);
  std::vector<std::int64_t> ticks(ts_dims[0]);
  const bool in_seconds = where.tick_ns == 0;
  if (ts_dims[0] > 0)
    readRows(ts.get(), path, where.times, 1, ts_dims, 0, ts_dims[0],
             in_seconds ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64,
             in_seconds ? static_cast<void*>(seconds.data()) : static_cast<void*>(ticks.data()));
  for (std::size_t i = 0; i < ts_dims[0]; ++i) {
    TimeNs t = 0;
    if (in_seconds ? !std::isfinite(seconds[i]) : __builtin_mul_overflow(ticks[i], where.tick_ns, &t))
      throw InputError(path,
                       where.times + "[" + std::to_string(i) + "] is not a time (not finite or too large)");
    frames.t.push_back(in_seconds ? fromSeconds(seconds[i]) : t);
    if (i > 0 && frames.t[i] <= frames.t[i - 1])
      throw InputError(path, where.times + "[" + std::to_string(i) + "]: times must increase");
  }
  frames.height = static_cast<int>(dims[1]);
  frames.width = static_cast<int>(dims[2]);
  return frames;
}

cv::Mat readHdf5Frame(const std::filesystem::path& file, const Hdf5FrameDatasets& where, std::size_t i) {
  const std::string path = file.string();
  Hid f = openFile(path);
  hsize_t dims[4] = {};
  Hid images = openFrames(f.get(), path, where.images, dims);
  if (i >= dims[0]) throw InputError(path, where.images + ": no image " + std::to_string(i));
  cv::Mat img(static_cast<int>(dims[1]), static_cast<int>(dims[2]), CV_8UC1);
  Hid space(H5Dget_space(images.get()), H5Sclose);
  readRows(images.get(), path, where.images, H5Sget_simple_extent_ndims(space.get()), dims, i, 1,
           H5T_NATIVE_UINT8, img.data);
  return img;
}

namespace {

bool exists(hid_t f, const std::string& name) {
  std::size_t slash = 0;
  while ((slash = name.find('/', slash + 1)) != std::string::npos)
    if (H5Lexists(f, name.substr(0, slash).c_str(), H5P_DEFAULT) <= 0) return false;
  return H5Lexists(f, name.c_str(), H5P_DEFAULT) > 0;
}

std::vector<double> readNumbers(hid_t f, const std::string& path, const std::string& name, hsize_t count) {
  Hid ds(H5Dopen2(f, name.c_str(), H5P_DEFAULT), H5Dclose);
  Hid space(ds.valid() ? H5Dget_space(ds.get()) : H5I_INVALID_HID, H5Sclose);
  std::vector<double> v(count);
  if (!space.valid() || H5Sget_simple_extent_npoints(space.get()) != static_cast<hssize_t>(count) ||
      H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
    throw InputError(path, name + " is not " + std::to_string(count) + " numbers");
  return v;
}

// A scalar string dataset, fixed or variable length (h5py writes Python strings as the latter).
std::string readString(hid_t f, const std::string& path, const std::string& name) {
  Hid ds(H5Dopen2(f, name.c_str(), H5P_DEFAULT), H5Dclose);
  Hid type(ds.valid() ? H5Dget_type(ds.get()) : H5I_INVALID_HID, H5Tclose);
  if (!type.valid() || H5Tget_class(type.get()) != H5T_STRING)
    throw InputError(path, name + " is not a string");
  if (H5Tis_variable_str(type.get()) > 0) {
    char* s = nullptr;
    Hid mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem.get(), H5T_VARIABLE);
    H5Tset_cset(mem.get(), H5Tget_cset(type.get()));  // h5py writes UTF-8
    if (H5Dread(ds.get(), mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &s) < 0)
      hdf5::failH5(path, "cannot read " + name);
    const std::string out = s ? s : "";
    H5free_memory(s);
    return out;
  }
  std::string s(H5Tget_size(type.get()), '\0');
  if (H5Dread(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data()) < 0)
    hdf5::failH5(path, "cannot read " + name);
  return s.substr(0, s.find('\0'));
}

CameraModel readM3edCamera(hid_t f, const std::string& path, const std::string& calib) {
  CameraModel c;
  const std::vector<double> k = readNumbers(f, path, calib + "/intrinsics", 4);
  const std::vector<double> size = readNumbers(f, path, calib + "/resolution", 2);
  c.fx = k[0], c.fy = k[1], c.cx = k[2], c.cy = k[3];
  c.width = static_cast<int>(size[0]), c.height = static_cast<int>(size[1]);
  const std::string model = readString(f, path, calib + "/distortion_model");
  if (model != "radtan" && model != "equidistant")
    throw InputError(path, calib + "/distortion_model '" + model + "' is not radtan or equidistant");
  c.distortion = model == "radtan" ? Distortion::kRadTan : Distortion::kEquidistant;
  const std::vector<double> d = readNumbers(f, path, calib + "/distortion_coeffs", 4);
  std::copy(d.begin(), d.end(), c.k.begin());
  try {
    c.validate(path + ": " + calib);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, e.what());
  }
  return c;
}

}  // namespace

M3edCalibration readM3edCalibration(const std::filesystem::path& file) {
  const std::string path = file.string();
  Hid f = openFile(path);
  hdf5::QuietHdf5 quiet;
  M3edCalibration m;
  if (exists(f.get(), "prophesee/left/calib/intrinsics"))
    m.events = readM3edCamera(f.get(), path, "prophesee/left/calib");
  if (exists(f.get(), "ovc/left/calib/T_to_prophesee_left")) {
    const std::vector<double> T = readNumbers(f.get(), path, "ovc/left/calib/T_to_prophesee_left", 16);
    for (int i = 0; i < 16; ++i)
      m.frames_from_another_camera |= std::abs(T[i] - (i % 5 == 0 ? 1.0 : 0.0)) > 1e-9;
  }
  if (m.events && exists(f.get(), "ovc/left/calib/resolution")) {
    const std::vector<double> size = readNumbers(f.get(), path, "ovc/left/calib/resolution", 2);
    m.frames_from_another_camera |= size[0] != m.events->width || size[1] != m.events->height;
  }
  return m;
}

struct MvsecEventSource::Impl {
  std::string path, name;
  int width, height;
  Hid file, events;
  hsize_t dims[2] = {};
  hsize_t row = 0;
  std::vector<double> rows;
  TimeNs last_t = std::numeric_limits<TimeNs>::min();
};

MvsecEventSource::MvsecEventSource(const std::filesystem::path& file, int width, int height,
                                   const std::string& side)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = file.string();
  m.name = "davis/" + side + "/events";
  m.width = width;
  m.height = height;
  m.file = openFile(m.path);
  m.events = openArray(m.file.get(), m.path, m.name, 2, m.dims);
  if (m.dims[1] != 4)
    throw InputError(m.path, m.name + " has " + std::to_string(m.dims[1]) + " columns, not 4 (x, y, t, p)");
}

MvsecEventSource::~MvsecEventSource() = default;
std::optional<std::size_t> MvsecEventSource::size() const { return static_cast<std::size_t>(impl_->dims[0]); }

bool MvsecEventSource::decodeNextBlock(EventArray& block) {
  Impl& m = *impl_;
  if (m.row >= m.dims[0]) return false;
  const hsize_t n = std::min(kBlockRows, m.dims[0] - m.row);
  m.rows.resize(4 * n);
  readRows(m.events.get(), m.path, m.name, 2, m.dims, m.row, n, H5T_NATIVE_DOUBLE, m.rows.data());
  block.resize(n);
  for (hsize_t i = 0; i < n; ++i) {
    const double* r = &m.rows[4 * i];
    const std::string at = m.name + "[" + std::to_string(m.row + i) + "]";
    if (!std::isfinite(r[0]) || !std::isfinite(r[1]) || !std::isfinite(r[2]))
      throw InputError(m.path, at + " is not finite");
    if (r[0] < 0 || r[1] < 0 || r[0] != std::floor(r[0]) || r[1] != std::floor(r[1]) ||
        (m.width > 0 && (r[0] >= m.width || r[1] >= m.height)))
      throw InputError(m.path, at + ": pixel (" + std::to_string(r[0]) + ", " + std::to_string(r[1]) +
                                   ") is not a pixel of the " + std::to_string(m.width) + "x" +
                                   std::to_string(m.height) + " sensor");
    const TimeNs t = fromSeconds(r[2]);
    if (t < m.last_t) throw InputError(m.path, at + ": time " + std::to_string(r[2]) + " s goes back");
    m.last_t = t;
    block.t[i] = t;
    block.x[i] = static_cast<std::uint16_t>(r[0]);
    block.y[i] = static_cast<std::uint16_t>(r[1]);
    block.p[i] = r[3] > 0 ? 1 : -1;
  }
  m.row += n;
  return true;
}

}  // namespace eds
