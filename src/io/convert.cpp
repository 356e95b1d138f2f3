#include "io/convert.hpp"

#include "io/eds_hdf5.hpp"

namespace eds {

ConvertCounts convertToEdsHdf5(const Sequence& seq, const std::filesystem::path& target, bool compress) {
  EdsHdf5Writer writer(target, seq.format(), compress);
  EdsHdf5Contents rest;
  ConvertCounts n;
  rest.width = seq.width();
  rest.height = seq.height();
  if (seq.hasEvents()) {
    const auto src = seq.openEvents();
    constexpr std::size_t kChunk = 1 << 16;
    EventArray chunk;
    chunk.reserve(kChunk);
    for (chunk.clear(); src->read(chunk, kChunk) > 0; chunk.clear()) {
      writer.appendEvents(chunk);
      n.events += chunk.size();
    }
    rest.triggers = src->triggers();
  }
  for (std::size_t i = 0; i < seq.frames().size(); ++i)
    writer.appendFrame(seq.frames()[i].t, seq.loadFrame(i));
  if (seq.hasCalibration()) {
    rest.camera = seq.camera();
    rest.calibration_source = seq.calibrationSource();
  }
  if (seq.hasGroundTruth()) rest.ground_truth = seq.groundTruth();
  rest.imu = seq.imu();
  writer.finish(rest);
  n.frames = seq.frames().size();
  n.ground_truth = rest.ground_truth.size();
  n.imu = rest.imu.size();
  n.triggers = rest.triggers.size();
  n.calibration = rest.camera.has_value();
  return n;
}

}  // namespace eds
