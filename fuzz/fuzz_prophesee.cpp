// Prophesee EVT 2.0 / 3.0 .raw files: header, then words decoded into events.
#include "fuzz_input.hpp"
#include "io/prophesee.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "recording.raw");
  eds::fuzz::expectOnlyInputErrors([&] {
    eds::PropheseeRawSource src(file);
    eds::EventArray out;
    while (src.read(out, 4096) > 0) out.clear();
  });
  return 0;
}
