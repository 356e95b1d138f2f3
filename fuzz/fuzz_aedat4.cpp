// AEDAT 4.0: header, packets (lz4/zstd), events, frames, IMU and trigger tables.
#include "fuzz_input.hpp"
#include "io/aedat4.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "recording.aedat4");
  eds::fuzz::expectOnlyInputErrors([&] {
    const eds::Aedat4Counts counts = eds::scanAedat4(file);
    for (const eds::Aedat4Frame& f : counts.frames) eds::readAedat4Frame(file, f.packet_offset);
  });
  eds::fuzz::expectOnlyInputErrors([&] {
    eds::Aedat4EventSource src(file);
    eds::EventArray out;
    while (src.read(out, 4096) > 0) out.clear();
  });
  return 0;
}
