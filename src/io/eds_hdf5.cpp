#include "io/eds_hdf5.hpp"

#include <hdf5.h>

#include <array>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "io/hdf5_common.hpp"
#include "io/output_file.hpp"

namespace eds {

using hdf5::failH5;
using hdf5::Hid;
using hdf5::QuietHdf5;

namespace {

constexpr TimeNs kNsPerMs = 1'000'000;
constexpr std::array<const char*, 3> kModels = {"none", "radtan", "equidistant"};

// A dataset of rows that grows as rows are appended (chunked, unlimited first dimension).
class Appendable {
 public:
  Appendable() = default;
  Appendable(hid_t file, const std::string& path, const char* name, hid_t file_type,
             std::vector<hsize_t> row_shape, hsize_t chunk_rows, bool compress)
      : path_(path), name_(name), shape_(std::move(row_shape)) {
    shape_.insert(shape_.begin(), 0);
    std::vector<hsize_t> max = shape_, chunk = shape_;
    max[0] = H5S_UNLIMITED;
    chunk[0] = chunk_rows;
    Hid space(H5Screate_simple(static_cast<int>(shape_.size()), shape_.data(), max.data()), H5Sclose);
    Hid dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data());
    if (compress) {
      H5Pset_shuffle(dcpl.get());
      H5Pset_deflate(dcpl.get(), 1);
    }
    Hid lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
    H5Pset_create_intermediate_group(lcpl.get(), 1);
    ds_ = Hid(H5Dcreate2(file, name, file_type, space.get(), lcpl.get(), dcpl.get(), H5P_DEFAULT), H5Dclose);
    if (!ds_.valid()) failH5(path, std::string("cannot create ") + name);
  }

  bool valid() const { return ds_.valid(); }
  void close() { ds_.reset(); }

  void append(hid_t mem_type, const void* data, hsize_t rows) {
    if (rows == 0) return;
    std::vector<hsize_t> start(shape_.size(), 0), count = shape_;
    start[0] = shape_[0];
    count[0] = rows;
    shape_[0] += rows;
    Hid mem(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr), H5Sclose);
    if (H5Dset_extent(ds_.get(), shape_.data()) < 0) failH5(path_, "cannot extend " + name_);
    Hid space(H5Dget_space(ds_.get()), H5Sclose);
    H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
    if (H5Dwrite(ds_.get(), mem_type, mem.get(), space.get(), H5P_DEFAULT, data) < 0)
      failH5(path_, "cannot write " + name_);
  }

 private:
  std::string path_, name_;
  std::vector<hsize_t> shape_;
  Hid ds_;
};

void writeArray(hid_t file, const std::string& path, const char* name, hid_t file_type, hid_t mem_type,
                const void* data, std::vector<hsize_t> dims) {
  Appendable a(file, path, name, file_type, std::vector<hsize_t>(dims.begin() + 1, dims.end()),
               std::max<hsize_t>(dims[0], 1), false);
  a.append(mem_type, data, dims[0]);
}

void setAttr(hid_t obj, const std::string& path, const char* name, hid_t type, const void* value,
             hsize_t n = 1) {
  Hid space(n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), H5Sclose);
  Hid a(H5Acreate2(obj, name, type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.valid() || H5Awrite(a.get(), type, value) < 0)
    failH5(path, std::string("cannot write attribute ") + name);
}

void setStringAttr(hid_t obj, const std::string& path, const char* name, const std::string& value) {
  Hid type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), std::max<std::size_t>(value.size(), 1));
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  setAttr(obj, path, name, type.get(), padded.data());
}

void writeCalibration(hid_t file, const std::string& path, const CameraModel& cam,
                      const std::string& source) {
  Hid g(H5Gcreate2(file, "calibration", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!g.valid()) failH5(path, "cannot create group calibration");
  setStringAttr(g.get(), path, "model", kModels[static_cast<std::size_t>(cam.distortion)]);
  setStringAttr(g.get(), path, "source", source);
  setAttr(g.get(), path, "width", H5T_NATIVE_INT, &cam.width);
  setAttr(g.get(), path, "height", H5T_NATIVE_INT, &cam.height);
  const std::array<std::pair<const char*, double>, 4> f = {
      {{"fx", cam.fx}, {"fy", cam.fy}, {"cx", cam.cx}, {"cy", cam.cy}}};
  for (const auto& [name, v] : f) setAttr(g.get(), path, name, H5T_NATIVE_DOUBLE, &v);
  setAttr(g.get(), path, "k", H5T_NATIVE_DOUBLE, cam.k.data(), cam.k.size());
}

void writeStreams(hid_t file, const std::string& path, const EdsHdf5Contents& c) {
  const auto times = [&](const char* name, const auto& items) {
    std::vector<std::int64_t> t;
    for (const auto& s : items) t.push_back(s.t);
    writeArray(file, path, name, H5T_STD_I64LE, H5T_NATIVE_INT64, t.data(), {t.size()});
  };
  if (!c.ground_truth.empty()) {
    std::vector<double> rows;
    for (const StampedPose& p : c.ground_truth) {
      const Vec3& t = p.T_w_c.translation();
      const Quat& q = p.T_w_c.quaternion();
      rows.insert(rows.end(), {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()});
    }
    times("ground_truth/t", c.ground_truth);
    writeArray(file, path, "ground_truth/T_w_c", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, rows.data(),
               {c.ground_truth.size(), 7});
  }
  if (!c.imu.empty()) {
    std::vector<double> acc, gyro;
    for (const ImuSample& s : c.imu) {
      acc.insert(acc.end(), s.acc, s.acc + 3);
      gyro.insert(gyro.end(), s.gyro, s.gyro + 3);
    }
    times("imu/t", c.imu);
    writeArray(file, path, "imu/acc", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, acc.data(), {c.imu.size(), 3});
    writeArray(file, path, "imu/gyro", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, gyro.data(), {c.imu.size(), 3});
  }
  if (!c.triggers.empty()) {
    std::vector<std::uint8_t> channel, rising;
    for (const TriggerEvent& e : c.triggers) channel.push_back(e.channel), rising.push_back(e.rising ? 1 : 0);
    times("triggers/t", c.triggers);
    writeArray(file, path, "triggers/channel", H5T_STD_U8LE, H5T_NATIVE_UINT8, channel.data(),
               {channel.size()});
    writeArray(file, path, "triggers/rising", H5T_STD_U8LE, H5T_NATIVE_UINT8, rising.data(), {rising.size()});
  }
}

}  // namespace

struct EdsHdf5Writer::Impl {
  std::string path;  // the temporary file, named in errors
  OutputFile out;
  bool compress = false;
  Hid file;
  Appendable t, x, y, p, images, frame_t;
  std::vector<std::uint64_t> ms_to_idx;
  std::uint64_t events = 0;
  TimeNs t_offset = 0, last_t = 0, last_frame_t = 0;
  int width = 0, height = 0;
  std::vector<std::int64_t> t_rel;
  std::vector<std::uint8_t> p01;

  explicit Impl(const std::filesystem::path& target) : out(target) {}
};

EdsHdf5Writer::EdsHdf5Writer(const std::filesystem::path& target, const std::string& source_format,
                             bool compress)
    : impl_(std::make_unique<Impl>(target)) {
  Impl& m = *impl_;
  QuietHdf5 quiet;
  m.path = m.out.temporary().string();
  m.compress = compress;
  m.file = Hid(H5Fcreate(m.path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
  if (!m.file.valid()) failH5(target.string(), "cannot create the HDF5 file");
  const int version = 1;
  setAttr(m.file.get(), m.path, "eds_layout", H5T_NATIVE_INT, &version);
  setStringAttr(m.file.get(), m.path, "source_format", source_format);
}

EdsHdf5Writer::~EdsHdf5Writer() {
  QuietHdf5 quiet;
  impl_.reset();
}

void EdsHdf5Writer::appendEvents(const EventArray& ev) {
  Impl& m = *impl_;
  if (ev.size() == 0) return;
  QuietHdf5 quiet;
  if (!m.t.valid()) {
    constexpr hsize_t kChunk = 1 << 16;
    m.t = Appendable(m.file.get(), m.path, "events/t", H5T_STD_I64LE, {}, kChunk, m.compress);
    m.x = Appendable(m.file.get(), m.path, "events/x", H5T_STD_U16LE, {}, kChunk, m.compress);
    m.y = Appendable(m.file.get(), m.path, "events/y", H5T_STD_U16LE, {}, kChunk, m.compress);
    m.p = Appendable(m.file.get(), m.path, "events/p", H5T_STD_U8LE, {}, kChunk, m.compress);
    // Times are kept relative to the first event's millisecond, so that ms_to_idx starts at 0.
    m.t_offset = ev.t[0] - ((ev.t[0] % kNsPerMs) + kNsPerMs) % kNsPerMs;
    m.last_t = ev.t[0];
  }
  const std::size_t n = ev.size();
  m.t_rel.resize(n);
  m.p01.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (ev.t[i] < m.last_t)
      throw std::invalid_argument("EdsHdf5Writer: event " + std::to_string(m.events + i) +
                                  " goes back in time");
    m.last_t = ev.t[i];
    m.t_rel[i] = ev.t[i] - m.t_offset;
    while (static_cast<TimeNs>(m.ms_to_idx.size()) * kNsPerMs <= m.t_rel[i])
      m.ms_to_idx.push_back(m.events + i);
    m.p01[i] = ev.p[i] > 0 ? 1 : 0;
  }
  m.t.append(H5T_NATIVE_INT64, m.t_rel.data(), n);
  m.x.append(H5T_NATIVE_UINT16, ev.x.data(), n);
  m.y.append(H5T_NATIVE_UINT16, ev.y.data(), n);
  m.p.append(H5T_NATIVE_UINT8, m.p01.data(), n);
  m.events += n;
}

void EdsHdf5Writer::appendFrame(TimeNs t, const cv::Mat& gray) {
  Impl& m = *impl_;
  if (gray.type() != CV_8UC1) throw std::invalid_argument("EdsHdf5Writer: frames must be 8-bit gray");
  QuietHdf5 quiet;
  if (!m.images.valid()) {
    m.width = gray.cols, m.height = gray.rows;
    const auto h = static_cast<hsize_t>(gray.rows), w = static_cast<hsize_t>(gray.cols);
    m.images = Appendable(m.file.get(), m.path, "frames/images", H5T_STD_U8LE, {h, w}, 1, m.compress);
    m.frame_t = Appendable(m.file.get(), m.path, "frames/t", H5T_STD_I64LE, {}, 1024, false);
  } else if (gray.cols != m.width || gray.rows != m.height || t <= m.last_frame_t) {
    throw std::invalid_argument("EdsHdf5Writer: frames must share one size and come in increasing time");
  }
  const cv::Mat packed = gray.isContinuous() ? gray : gray.clone();
  m.images.append(H5T_NATIVE_UINT8, packed.data, 1);
  m.frame_t.append(H5T_NATIVE_INT64, &t, 1);
  m.last_frame_t = t;
}

void EdsHdf5Writer::finish(const EdsHdf5Contents& rest) {
  Impl& m = *impl_;
  QuietHdf5 quiet;
  if (m.events > 0) {
    m.ms_to_idx.push_back(m.events);  // the end of the last millisecond
    writeArray(m.file.get(), m.path, "ms_to_idx", H5T_STD_U64LE, H5T_NATIVE_UINT64, m.ms_to_idx.data(),
               {m.ms_to_idx.size()});
    Hid scalar(H5Screate(H5S_SCALAR), H5Sclose);
    Hid ds(H5Dcreate2(m.file.get(), "t_offset", H5T_STD_I64LE, scalar.get(), H5P_DEFAULT, H5P_DEFAULT,
                      H5P_DEFAULT),
           H5Dclose);
    if (!ds.valid() || H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &m.t_offset) < 0)
      failH5(m.path, "cannot write t_offset");
  }
  setAttr(m.file.get(), m.path, "width", H5T_NATIVE_INT, &rest.width);
  setAttr(m.file.get(), m.path, "height", H5T_NATIVE_INT, &rest.height);
  if (rest.camera) writeCalibration(m.file.get(), m.path, *rest.camera, rest.calibration_source);
  writeStreams(m.file.get(), m.path, rest);
  for (Appendable* a : {&m.t, &m.x, &m.y, &m.p, &m.images, &m.frame_t}) a->close();
  if (H5Fflush(m.file.get(), H5F_SCOPE_LOCAL) < 0) failH5(m.path, "cannot write the HDF5 file");
  m.file.reset();
  m.out.commit();
}

}  // namespace eds

namespace eds {
namespace {

// A whole small dataset (N or N x cols) as `mem_type`; InputError naming it when its shape differs.
template <typename T>
std::vector<T> readAll(hid_t file, const std::string& path, const char* name, hid_t mem_type, hsize_t cols,
                       hsize_t rows_expected = 0) {
  if (H5Lexists(file, std::string(name).substr(0, std::string(name).find('/')).c_str(), H5P_DEFAULT) <= 0 ||
      H5Lexists(file, name, H5P_DEFAULT) <= 0)
    throw InputError(path, std::string("missing dataset ") + name);
  Hid ds(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) failH5(path, std::string(name) + " is not a dataset");
  Hid space(H5Dget_space(ds.get()), H5Sclose);
  hsize_t dims[2] = {0, 1};
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank != (cols == 1 ? 1 : 2) || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0 ||
      dims[1] != cols || (rows_expected > 0 && dims[0] != rows_expected))
    throw InputError(path, std::string(name) + " is not an array of " +
                               (rows_expected > 0 ? std::to_string(rows_expected) : std::string("N")) +
                               " x " + std::to_string(cols));
  std::vector<T> v(dims[0] * cols);
  if (!v.empty() && H5Dread(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
    failH5(path, std::string("cannot read ") + name);
  return v;
}

std::vector<TimeNs> readTimes(hid_t file, const std::string& path, const char* name) {
  std::vector<TimeNs> t = readAll<TimeNs>(file, path, name, H5T_NATIVE_INT64, 1);
  for (std::size_t i = 1; i < t.size(); ++i)
    if (t[i] < t[i - 1])
      throw InputError(path, std::string(name) + "[" + std::to_string(i) + "]: times must not decrease");
  return t;
}

bool exists(hid_t file, const char* name) { return H5Lexists(file, name, H5P_DEFAULT) > 0; }

std::string stringAttr(hid_t obj, const std::string& path, const char* name) {
  if (H5Aexists(obj, name) <= 0) return {};
  Hid a(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  Hid type(H5Aget_type(a.get()), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_STRING || H5Tis_variable_str(type.get()) > 0)
    throw InputError(path, std::string("attribute ") + name + " is not a fixed-length string");
  std::string s(H5Tget_size(type.get()), '\0');
  if (H5Aread(a.get(), type.get(), s.data()) < 0) failH5(path, std::string("cannot read attribute ") + name);
  return s.substr(0, s.find('\0'));
}

template <typename T>
T numberAttr(hid_t obj, const std::string& path, const char* name, hid_t mem_type, std::size_t n = 1) {
  T v{};
  Hid a(H5Aexists(obj, name) > 0 ? H5Aopen(obj, name, H5P_DEFAULT) : H5I_INVALID_HID, H5Aclose);
  Hid space(a.valid() ? H5Aget_space(a.get()) : H5I_INVALID_HID, H5Sclose);
  if (!a.valid() || H5Sget_simple_extent_npoints(space.get()) != static_cast<hssize_t>(n) ||
      H5Aread(a.get(), mem_type, &v) < 0)
    throw InputError(path, std::string("attribute ") + name + " is missing or malformed");
  return v;
}

CameraModel readCalibration(hid_t file, const std::string& path) {
  Hid g(H5Gopen2(file, "calibration", H5P_DEFAULT), H5Gclose);
  if (!g.valid()) failH5(path, "calibration is not a group");
  CameraModel c;
  const std::string model = stringAttr(g.get(), path, "model");
  const auto it = std::find(kModels.begin(), kModels.end(), model);
  if (it == kModels.end())
    throw InputError(path, "calibration model '" + model + "' is not none/radtan/equidistant");
  c.distortion = static_cast<Distortion>(it - kModels.begin());
  c.width = numberAttr<int>(g.get(), path, "width", H5T_NATIVE_INT);
  c.height = numberAttr<int>(g.get(), path, "height", H5T_NATIVE_INT);
  c.fx = numberAttr<double>(g.get(), path, "fx", H5T_NATIVE_DOUBLE);
  c.fy = numberAttr<double>(g.get(), path, "fy", H5T_NATIVE_DOUBLE);
  c.cx = numberAttr<double>(g.get(), path, "cx", H5T_NATIVE_DOUBLE);
  c.cy = numberAttr<double>(g.get(), path, "cy", H5T_NATIVE_DOUBLE);
  c.k = numberAttr<std::array<double, 5>>(g.get(), path, "k", H5T_NATIVE_DOUBLE, 5);
  try {
    c.validate(path + " calibration");
  } catch (const std::invalid_argument& e) {
    throw InputError(path, e.what());
  }
  return c;
}

Trajectory readGroundTruth(hid_t file, const std::string& path) {
  const std::vector<TimeNs> t = readTimes(file, path, "ground_truth/t");
  const std::vector<double> rows =
      readAll<double>(file, path, "ground_truth/T_w_c", H5T_NATIVE_DOUBLE, 7, t.size());
  Trajectory gt(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double* r = &rows[7 * i];
    const Quat q(r[6], r[3], r[4], r[5]);
    if (!std::all_of(r, r + 7, [](double v) { return std::isfinite(v); }) || q.norm() < 1e-6)
      throw InputError(path, "ground_truth/T_w_c[" + std::to_string(i) + "] is not a pose");
    gt[i] = {t[i], SE3(q.normalized(), Vec3(r[0], r[1], r[2]))};
  }
  return gt;
}

std::vector<ImuSample> readImu(hid_t file, const std::string& path) {
  const std::vector<TimeNs> t = readTimes(file, path, "imu/t");
  const std::vector<double> acc = readAll<double>(file, path, "imu/acc", H5T_NATIVE_DOUBLE, 3, t.size());
  const std::vector<double> gyro = readAll<double>(file, path, "imu/gyro", H5T_NATIVE_DOUBLE, 3, t.size());
  std::vector<ImuSample> imu(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    imu[i].t = t[i];
    std::copy_n(&acc[3 * i], 3, imu[i].acc);
    std::copy_n(&gyro[3 * i], 3, imu[i].gyro);
  }
  return imu;
}

std::vector<TriggerEvent> readTriggers(hid_t file, const std::string& path) {
  const std::vector<TimeNs> t = readTimes(file, path, "triggers/t");
  const auto channel = readAll<std::uint8_t>(file, path, "triggers/channel", H5T_NATIVE_UINT8, 1, t.size());
  const auto rising = readAll<std::uint8_t>(file, path, "triggers/rising", H5T_NATIVE_UINT8, 1, t.size());
  std::vector<TriggerEvent> out(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) out[i] = {t[i], channel[i], rising[i] != 0};
  return out;
}

}  // namespace

EdsHdf5Contents readEdsHdf5(const std::filesystem::path& file) {
  const std::string path = file.string();
  QuietHdf5 quiet;
  Hid f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!f.valid()) failH5(path, "cannot open as HDF5");
  if (numberAttr<int>(f.get(), path, "eds_layout", H5T_NATIVE_INT) != 1)
    throw InputError(path, "eds_layout version is not 1");
  EdsHdf5Contents c;
  c.source_format = stringAttr(f.get(), path, "source_format");
  c.has_events = exists(f.get(), "events");
  if (H5Aexists(f.get(), "width") > 0) c.width = numberAttr<int>(f.get(), path, "width", H5T_NATIVE_INT);
  if (H5Aexists(f.get(), "height") > 0) c.height = numberAttr<int>(f.get(), path, "height", H5T_NATIVE_INT);
  if (c.width < 0 || c.height < 0) throw InputError(path, "negative sensor size");
  if (exists(f.get(), "calibration")) {
    c.camera = readCalibration(f.get(), path);
    Hid g(H5Gopen2(f.get(), "calibration", H5P_DEFAULT), H5Gclose);
    c.calibration_source = stringAttr(g.get(), path, "source");
  }
  if (exists(f.get(), "ground_truth")) c.ground_truth = readGroundTruth(f.get(), path);
  if (exists(f.get(), "imu")) c.imu = readImu(f.get(), path);
  if (exists(f.get(), "triggers")) c.triggers = readTriggers(f.get(), path);
  return c;
}

}  // namespace eds
