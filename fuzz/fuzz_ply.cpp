// PLY point clouds (map.ply of a run).
#include "fuzz_input.hpp"
#include "io/ply.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "map.ply");
  eds::fuzz::expectOnlyInputErrors([&] { eds::readPly(file); });
  return 0;
}
