// ECD events.txt: "t x y p" lines, read in chunks as eds run reads them.
#include "fuzz_input.hpp"
#include "io/ecd_events.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "events.txt");
  eds::fuzz::expectOnlyInputErrors([&] {
    eds::EcdEventSource src(file);
    eds::EventArray out;
    while (src.read(out, 1000) > 0) out.clear();
  });
  return 0;
}
