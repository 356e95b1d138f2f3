// ECD images.txt: "t path" lines.
#include "fuzz_input.hpp"
#include "io/sequence.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "images.txt");
  eds::fuzz::expectOnlyInputErrors([&] { eds::readImageList(file); });
  return 0;
}
