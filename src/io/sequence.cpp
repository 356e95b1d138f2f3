#include "io/sequence.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "io/aedat4.hpp"
#include "io/ecd_events.hpp"
#include "io/eds_hdf5.hpp"
#include "io/hdf5_events.hpp"
#include "io/hdf5_layouts.hpp"
#include "io/kalibr.hpp"
#include "io/line_reader.hpp"
#include "io/prophesee.hpp"
#include "io/ros_events.hpp"
#include "io/ros_recording.hpp"
#include "io/text_parse.hpp"

namespace eds {
namespace fs = std::filesystem;

CameraModel readEcdCalib(const fs::path& file) {
  LineReader reader(file);
  std::string_view line;
  std::vector<double> v;
  std::size_t line_no = 0;
  while (reader.next(line)) {
    const char* p = text::skipSpaces(line.data(), line.data() + line.size());
    const char* end = line.data() + line.size();
    if (p == end || *p == '#') continue;
    line_no = reader.lineNumber();
    while (p < end) {
      double d;
      const auto r = std::from_chars(p, end, d);
      if (r.ec != std::errc() || !text::atFieldEnd(r.ptr, end))
        throw InputError(reader.fileName(), line_no, "malformed number in '" + std::string(line) + "'");
      if (!std::isfinite(d)) throw InputError(reader.fileName(), line_no, "non-finite value (NaN or inf)");
      v.push_back(d);
      p = text::skipSpaces(r.ptr, end);
    }
    break;  // the calibration is the first non-comment line
  }
  if (v.empty()) throw InputError(reader.fileName(), "empty calibration file");
  if (v.size() != 4 && v.size() != 8 && v.size() != 9)
    throw InputError(
        reader.fileName(), line_no,
        "expected 'fx fy cx cy [k1 k2 p1 p2 [k3]]' (4, 8 or 9 numbers), got " + std::to_string(v.size()));
  CameraModel cam;
  cam.fx = v[0], cam.fy = v[1], cam.cx = v[2], cam.cy = v[3];
  for (std::size_t i = 4; i < v.size(); ++i) cam.k[i - 4] = v[i];
  bool any_distortion = false;
  for (double k : cam.k) any_distortion = any_distortion || k != 0.0;
  cam.distortion = any_distortion ? Distortion::kRadTan : Distortion::kNone;
  if (cam.fx <= 0 || cam.fy <= 0)
    throw InputError(reader.fileName(), line_no, "focal lengths must be positive");
  return cam;
}

CameraModel cameraFromKalibr(const KalibrCamera& k, const std::string& source) {
  CameraModel cam;
  cam.width = k.width;
  cam.height = k.height;
  cam.fx = k.fx, cam.fy = k.fy, cam.cx = k.cx, cam.cy = k.cy;
  if (k.distortion_model == "radtan") {
    cam.distortion = Distortion::kRadTan;
  } else if (k.distortion_model == "equidistant") {
    cam.distortion = Distortion::kEquidistant;
  } else if (k.distortion_model == "none" || k.distortion_model.empty()) {
    cam.distortion = Distortion::kNone;
  } else {
    throw InputError(source, "unsupported distortion_model '" + k.distortion_model + "'");
  }
  if (k.distortion_coeffs.size() > cam.k.size()) throw InputError(source, "too many distortion_coeffs");
  for (std::size_t i = 0; i < k.distortion_coeffs.size(); ++i) cam.k[i] = k.distortion_coeffs[i];
  try {
    cam.validate(source);
  } catch (const std::invalid_argument& e) {
    throw InputError(source, e.what());
  }
  return cam;
}

std::vector<FrameRef> readImageList(const fs::path& file) {
  LineReader reader(file);
  std::vector<FrameRef> frames;
  std::string_view line;
  const fs::path base = file.parent_path();
  while (reader.next(line)) {
    const char* p = text::skipSpaces(line.data(), line.data() + line.size());
    const char* end = line.data() + line.size();
    if (p == end || *p == '#') continue;
    const std::size_t ln = reader.lineNumber();
    TimeNs t;
    const char* q = text::parseSecondsNs(p, end, t);
    if (!q || !text::atFieldEnd(q, end))
      throw InputError(reader.fileName(), ln, "malformed timestamp in '" + std::string(line) + "'");
    q = text::skipSpaces(q, end);
    while (end > q && (end[-1] == ' ' || end[-1] == '\r' || end[-1] == '\t')) --end;
    if (q == end) throw InputError(reader.fileName(), ln, "missing image path (expected 't path')");
    const fs::path img = base / std::string(q, end);
    if (!frames.empty() && t <= frames.back().t)
      throw InputError(reader.fileName(), ln, "timestamps must increase");
    std::error_code ec;
    if (!fs::is_regular_file(img, ec))
      throw InputError(reader.fileName(), ln, "image file not found: " + img.string());
    frames.push_back({t, img});
  }
  if (frames.empty()) throw InputError(reader.fileName(), "no frames listed");
  return frames;
}

Sequence::Sequence(const fs::path& dir, const SequenceOptions& options) : dir_(dir), options_(options) {
  std::error_code ec;
  if (fs::is_regular_file(dir, ec) ||
      (fs::is_directory(dir, ec) && fs::is_regular_file(dir / "metadata.yaml", ec))) {
    openRecordingFile(dir);
    return;
  }
  if (!fs::is_directory(dir, ec))
    throw InputError(dir.string(), "sequence folder or recording file not found");
  for (const char* name : {"events.txt", "events.txt.gz", "events.h5"}) {
    if (fs::is_regular_file(dir / name, ec)) {
      events_file_ = dir / name;
      event_storage_ = fs::path(name).extension() == ".h5" ? EventStorage::kHdf5 : EventStorage::kEcdText;
      break;
    }
  }
  if (!events_file_.empty() && fs::file_size(events_file_, ec) == 0)
    throw InputError(events_file_.string(), "events file is empty");
  if (fs::is_regular_file(dir / "images.txt", ec)) frames_ = readImageList(dir / "images.txt");
  if (events_file_.empty() && frames_.empty())
    throw InputError(dir.string(), "holds neither events (events.txt[.gz], events.h5) nor images.txt");
  // A Kalibr camchain (with resolution) wins over calib.txt (without).
  for (const char* name : {"camchain.yaml", "calib.yaml"}) {
    if (fs::is_regular_file(dir / name, ec)) {
      camera_ = cameraFromKalibr(readKalibrCamera((dir / name).string()), (dir / name).string());
      calibration_source_ = (dir / name).string();
      width_ = camera_->width;
      height_ = camera_->height;
      break;
    }
  }
  if (!camera_ && fs::is_regular_file(dir / "calib.txt", ec)) {
    camera_ = readEcdCalib(dir / "calib.txt");
    calibration_source_ = (dir / "calib.txt").string();
  }
  if (!frames_.empty() && width_ == 0) {
    // ECD calib.txt has no resolution: the images give it.
    const cv::Mat first = loadFrame(0);
    width_ = first.cols;
    height_ = first.rows;
  } else if (!frames_.empty()) {
    loadFrame(0);  // checks the images against a Kalibr resolution
  }
  if (camera_) {
    camera_->width = width_;
    camera_->height = height_;
  }
}

void Sequence::setCamera(const CameraModel& camera, const std::string& source) {
  camera.validate(source);
  if ((camera.width > 0 && width_ > 0 && camera.width != width_) ||
      (camera.height > 0 && height_ > 0 && camera.height != height_))
    throw std::invalid_argument(source + ": calibration is " + std::to_string(camera.width) + "x" +
                                std::to_string(camera.height) + " but the sequence's images are " +
                                std::to_string(width_) + "x" + std::to_string(height_));
  camera_ = camera;
  calibration_source_ = source;
  if (width_ > 0)
    camera_->width = width_, camera_->height = height_;
  else
    width_ = camera.width, height_ = camera.height;
}

CameraModel readCameraFile(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".json") return readBasaltCalibration(file);
  if ((ext == ".yaml" || ext == ".yml") && isDsecCamToCam(file.string()))
    return cameraFromKalibr(readDsecCamera(file.string()), file.string());
  if (ext == ".yaml" || ext == ".yml")
    return cameraFromKalibr(readKalibrCamera(file.string()), file.string());
  return readEcdCalib(file);
}

CameraModel readBasaltCalibration(const fs::path& file, std::size_t camera) {
  const std::string name = file.string();
  std::ifstream in(file);
  if (!in) throw InputError(name, "file not found");
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(name, std::string("malformed JSON: ") + e.what());
  }
  try {
    const nlohmann::json& v = root.contains("value0") ? root.at("value0") : root;
    const nlohmann::json& cam = v.at("intrinsics").at(camera);
    const std::string type = cam.at("camera_type").get<std::string>();
    const nlohmann::json& k = cam.at("intrinsics");
    CameraModel c;
    c.fx = k.at("fx").get<double>(), c.fy = k.at("fy").get<double>();
    c.cx = k.at("cx").get<double>(), c.cy = k.at("cy").get<double>();
    if (type == "kb4") {  // Kannala-Brandt with k1..k4: the equidistant model
      c.distortion = Distortion::kEquidistant;
      for (int i = 0; i < 4; ++i) c.k[i] = k.at("k" + std::to_string(i + 1)).get<double>();
    } else if (type != "pinhole") {
      throw InputError(name, "camera_type '" + type + "' is not supported (kb4 and pinhole are)");
    }
    const nlohmann::json& res = v.at("resolution").at(camera);
    c.width = res.at(0).get<int>(), c.height = res.at(1).get<int>();
    c.validate(name);
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(
        name, std::string("not a Basalt calibration (value0.intrinsics, value0.resolution): ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(name, e.what());
  }
}

bool Sequence::hasGroundTruth() const {
  std::error_code ec;
  return !recorded_gt_.empty() || fs::is_regular_file(dir_ / "groundtruth.txt", ec);
}

const CameraModel& Sequence::camera() const {
  std::error_code ec;
  if (!camera_ && fs::is_regular_file(dir_, ec))
    throw InputError(dir_.string(), "the recording holds no calibration: give one with --calib FILE");
  if (!camera_) throw InputError((dir_ / "calib.txt").string(), "calibration file not found");
  return *camera_;
}

void Sequence::openRecordingFile(const fs::path& file) {
  events_file_ = file;
  const FileFormat file_format = sniffFileFormat(file);
  if (file_format == FileFormat::kAedat4) {
    const Aedat4Counts counts = scanAedat4(file);
    event_storage_ = EventStorage::kAedat4;
    format_ = "AEDAT 4.0";
    width_ = counts.width;
    height_ = counts.height;
    imu_ = counts.imu_samples;
    for (const Aedat4Frame& f : counts.frames) {
      if (!frames_.empty() && f.t <= frames_.back().t)
        throw errorAt(file.string(), f.packet_offset, "frame time stamps must increase");
      frames_.push_back({f.t, file, f.packet_offset, f.exposure});
    }
    if (counts.events == 0) events_file_.clear();
    return;
  }
  if (file_format == FileFormat::kPropheseeRaw) {
    const PropheseeHeader h = readPropheseeHeader(file);
    event_storage_ = EventStorage::kPropheseeRaw;
    format_ = h.format == EvtFormat::kEvt3   ? "Prophesee EVT 3.0"
              : h.format == EvtFormat::kEvt2 ? "Prophesee EVT 2.0"
                                             : "Prophesee DAT (CD events)";
    width_ = options_.width > 0 ? options_.width : h.width;
    height_ = options_.height > 0 ? options_.height : h.height;
    return;
  }
  if (detectRosContainer(file) != RosContainer::kNone) {
    openRosRecording(file);
    return;
  }
  const Hdf5Layout layout = file_format == FileFormat::kHdf5 ? detectHdf5Layout(file) : Hdf5Layout::kNone;
  if (layout == Hdf5Layout::kEds) {
    openEdsHdf5(file);
    return;
  }
  if (layout == Hdf5Layout::kMvsec || layout == Hdf5Layout::kM3ed) {
    event_storage_ = layout == Hdf5Layout::kMvsec ? EventStorage::kHdf5Mvsec : EventStorage::kHdf5;
    format_ =
        layout == Hdf5Layout::kMvsec ? "MVSEC HDF5 (davis/left)" : "M3ED HDF5 (prophesee/left, ovc/left)";
    hdf5_frames_ = frameDatasets(layout);
    const M3edCalibration m3ed = layout == Hdf5Layout::kM3ed ? readM3edCalibration(file) : M3edCalibration{};
    if (m3ed.events) {
      camera_ = m3ed.events;
      calibration_source_ = "prophesee/left/calib";
    }
    if (m3ed.frames_from_another_camera) {  // EDS needs frames of the event camera's own pixels
      hdf5_frames_ = {};
      format_ = "M3ED HDF5 (prophesee/left; the frames of ovc/left are another camera's and not read)";
    }
    const Hdf5FrameIndex frames = readHdf5FrameIndex(file, hdf5_frames_);
    for (std::size_t i = 0; i < frames.t.size(); ++i) frames_.push_back({frames.t[i], file, i});
    width_ = camera_ ? camera_->width : frames.width > 0 ? frames.width : options_.width;
    height_ = camera_ ? camera_->height : frames.height > 0 ? frames.height : options_.height;
    if (frames.width > 0 && (frames.width != width_ || frames.height != height_))
      throw InputError(file.string(), "frames of " + std::to_string(frames.width) + "x" +
                                          std::to_string(frames.height) + " but a calibration of " +
                                          std::to_string(width_) + "x" + std::to_string(height_));
    if (layout == Hdf5Layout::kM3ed) hdf5_group_ = "prophesee/left";
    return;
  }
  if (file_format == FileFormat::kHdf5) {
    event_storage_ = EventStorage::kHdf5;
    format_ = "HDF5 events";
    width_ = options_.width, height_ = options_.height;
    return;
  }
  throw InputError(
      file.string(),
      "not a recording eds reads (AEDAT 4.0, Prophesee .raw, ROS 1 bag, rosbag2 .db3/.mcap, HDF5 events), "
      "nor a sequence folder");
}

void Sequence::openRosRecording(const fs::path& file) {
  event_storage_ = EventStorage::kRosBag;
  const auto bag = openRosBag(file);
  format_ = bag->format();
  const bool any_events = std::any_of(bag->topics().begin(), bag->topics().end(),
                                      [](const RosTopic& t) { return isEventTopicType(t.type); });
  if (any_events || !options_.events_topic.empty()) {
    RosEventSource probe(file, options_.events_topic);
    format_ += ", events on " + probe.topic().name + " (" + probe.topic().type + ")";
    EventArray first;
    probe.read(first, 1);  // the sensor size is in the messages
    width_ = static_cast<int>(probe.stats().width);
    height_ = static_cast<int>(probe.stats().height);
  } else {
    events_file_.clear();
  }
  const RosRecordingIndex idx = indexRosRecording(file, {options_.image_topic, options_.gt_topic});
  if (!idx.image_topic.empty()) format_ += ", frames on " + idx.image_topic;
  for (const auto& f : idx.frames) frames_.push_back({f.t, file, f.message});
  recorded_gt_ = idx.ground_truth;
  imu_ = idx.imu_samples;
  if (!frames_.empty()) {
    ros_frames_ = std::make_shared<RosFrameLoader>(file);
    const cv::Mat first = loadFrame(0);
    if (width_ > 0 && (first.cols != width_ || first.rows != height_))
      throw InputError(file.string(), "frames of " + std::to_string(first.cols) + "x" +
                                          std::to_string(first.rows) + " but events of a " +
                                          std::to_string(width_) + "x" + std::to_string(height_) + " sensor");
    width_ = first.cols;
    height_ = first.rows;
  }
  if (idx.camera) {
    camera_ = idx.camera;
    calibration_source_ = "CameraInfo on " + idx.camera_info_topic;
    if (width_ > 0 && (camera_->width != width_ || camera_->height != height_))
      throw InputError(file.string(), "CameraInfo on " + idx.camera_info_topic + " is " +
                                          std::to_string(camera_->width) + "x" +
                                          std::to_string(camera_->height) + ", the sensor " +
                                          std::to_string(width_) + "x" + std::to_string(height_));
  }
}

void Sequence::openEdsHdf5(const fs::path& file) {
  EdsHdf5Contents c = readEdsHdf5(file);
  event_storage_ = EventStorage::kHdf5Eds;
  format_ = "eds HDF5" + (c.source_format.empty() ? std::string() : " (from " + c.source_format + ")");
  hdf5_frames_ = frameDatasets(Hdf5Layout::kEds);
  const Hdf5FrameIndex frames = readHdf5FrameIndex(file, hdf5_frames_);
  for (std::size_t i = 0; i < frames.t.size(); ++i) frames_.push_back({frames.t[i], file, i});
  width_ = c.width > 0 ? c.width : options_.width;
  height_ = c.height > 0 ? c.height : options_.height;
  const auto mismatch = [&](const char* what, int w, int h) {
    if (w > 0 && width_ > 0 && (w != width_ || h != height_))
      throw InputError(file.string(), std::string(what) + " of " + std::to_string(w) + "x" +
                                          std::to_string(h) + " on a " + std::to_string(width_) + "x" +
                                          std::to_string(height_) + " sensor");
  };
  mismatch("frames", frames.width, frames.height);
  if (c.camera) mismatch("calibration", c.camera->width, c.camera->height);
  if (width_ == 0) width_ = frames.width > 0 ? frames.width : c.camera ? c.camera->width : 0;
  if (height_ == 0) height_ = frames.height > 0 ? frames.height : c.camera ? c.camera->height : 0;
  camera_ = c.camera;
  calibration_source_ = c.calibration_source;
  recorded_gt_ = std::move(c.ground_truth);
  imu_ = std::move(c.imu);
  recorded_triggers_ = std::move(c.triggers);
  if (!c.has_events) events_file_.clear();
}

fs::path Sequence::framesSource() const {
  std::error_code ec;
  return fs::is_regular_file(dir_, ec) ? dir_ : dir_ / "images.txt";
}

std::unique_ptr<EventSource> Sequence::openEvents() const {
  if (events_file_.empty())
    throw InputError((dir_ / "events.txt").string(), "file not found (this sequence has no events)");
  if (event_storage_ == EventStorage::kPropheseeRaw)
    return std::make_unique<PropheseeRawSource>(events_file_, PropheseeOptions{width_, height_});
  if (event_storage_ == EventStorage::kRosBag)
    return std::make_unique<RosEventSource>(events_file_, options_.events_topic);
  if (event_storage_ == EventStorage::kAedat4) return std::make_unique<Aedat4EventSource>(events_file_);
  if (event_storage_ == EventStorage::kHdf5Mvsec)
    return std::make_unique<MvsecEventSource>(events_file_, width_, height_);
  if (event_storage_ == EventStorage::kHdf5 || event_storage_ == EventStorage::kHdf5Eds) {
    Hdf5EventOptions opts;
    opts.width = width_;
    opts.height = height_;
    if (event_storage_ == EventStorage::kHdf5Eds) {
      opts.tick_ns = 1;
      opts.triggers = recorded_triggers_;
    }
    if (!hdf5_group_.empty()) {
      opts.group = hdf5_group_;
      opts.ms_index = hdf5_group_ + "/ms_map_idx";
    }
    return std::make_unique<Hdf5EventSource>(events_file_.string(), opts);
  }
  EcdEventOptions opts;
  opts.width = width_;
  opts.height = height_;
  return std::make_unique<EcdEventSource>(events_file_, opts);
}

cv::Mat Sequence::loadFrame(std::size_t i) const {
  if (i >= frames_.size()) throw std::out_of_range("Sequence::loadFrame: frame index out of range");
  const std::string path = frames_[i].path.string();
  cv::Mat img = event_storage_ == EventStorage::kAedat4 ? readAedat4Frame(frames_[i].path, frames_[i].offset)
                : !hdf5_frames_.images.empty()
                    ? readHdf5Frame(frames_[i].path, hdf5_frames_, frames_[i].offset)
                : ros_frames_ ? ros_frames_->load(frames_[i].offset)
                              : cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw InputError(path, "cannot read image (missing or not an image)");
  if (width_ > 0 && (img.cols != width_ || img.rows != height_))
    throw InputError(path, "image size " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                               " differs from the sequence's " + std::to_string(width_) + "x" +
                               std::to_string(height_));
  return img;
}

std::optional<cv::Mat> Sequence::loadDepth(std::size_t i) const {
  if (i >= frames_.size()) throw std::out_of_range("Sequence::loadDepth: frame index out of range");
  const fs::path path = dir_ / "depth" / frames_[i].path.filename();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return std::nullopt;
  cv::Mat mm = cv::imread(path.string(), cv::IMREAD_ANYDEPTH);
  if (mm.empty() || mm.type() != CV_16U)
    throw InputError(path.string(), "depth map must be a uint16 PNG (mm)");
  cv::Mat metres;
  mm.convertTo(metres, CV_32F, 1e-3);
  return metres;
}

Trajectory Sequence::groundTruth() const {
  return recorded_gt_.empty() ? readTum(dir_ / "groundtruth.txt") : recorded_gt_;
}

}  // namespace eds
