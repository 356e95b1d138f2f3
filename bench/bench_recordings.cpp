// Read throughput of the recording readers on one thread: every event of a file, through the
// Sequence's event source (the format told by content), in 50k-event chunks. The files are the real
// samples in ../shared/data/real, or those listed in EDS_BENCH_RECORDINGS (colon-separated), read
// again and again from the page cache. Reports events per second. Also a long EVT 3.0 stream made from
// the short sample.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "io/prophesee.hpp"
#include "io/sequence.hpp"

namespace {

namespace fs = std::filesystem;

std::vector<fs::path> recordings() {
  std::vector<fs::path> files;
  if (const char* env = std::getenv("EDS_BENCH_RECORDINGS")) {
    std::stringstream ss(env);
    for (std::string f; std::getline(ss, f, ':');)
      if (!f.empty()) files.emplace_back(f);
    return files;
  }
  const fs::path real = fs::path(EDS_SHARED_DATA) / "real";
  for (const char* f : {"prophesee/evt2_gen3_640x480.raw", "prophesee/evt3_gen41_1280x720.raw",
                        "aedat4/davis346_indoor.aedat4", "ros2_and_ros1_event_camera_msgs/test_events_1.bag",
                        "ros2_and_ros1_event_camera_msgs/test_events_1"})
    if (fs::exists(real / f)) files.push_back(real / f);
  return files;
}

void readRecording(benchmark::State& state, const fs::path& file) {
  const eds::Sequence seq(file);
  eds::EventArray chunk;
  chunk.reserve(50000);
  std::size_t events = 0;
  for (auto _ : state) {
    auto src = seq.openEvents();
    while (true) {
      chunk.clear();
      const std::size_t n = src->read(chunk, 50000);
      if (n == 0) break;
      events += n;
    }
    benchmark::DoNotOptimize(chunk.t.data());
  }
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
  state.SetLabel(seq.format());
}

// The EVT 3.0 sample is 9 ms long, so reading it measures opening a file as much as decoding. This
// writes its words `copies` times one after another, each copy's TIME_HIGH words moved on by the span
// of the one before, for a stream long enough to measure the decoder.
fs::path longEvt3(const fs::path& sample, int copies) {
  const eds::PropheseeHeader h = eds::readPropheseeHeader(sample);
  std::ifstream in(sample, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::uint16_t> words((bytes.size() - h.data_offset) / 2);
  std::memcpy(words.data(), bytes.data() + h.data_offset, words.size() * 2);
  unsigned first = 0, last = 0;
  for (std::uint16_t w : words)
    if (w >> 12 == 0x8) (first == 0 ? first : last) = w & 0xFFF, last = w & 0xFFF;
  const fs::path out = fs::temp_directory_path() / "eds_bench_evt3_long.raw";
  std::ofstream o(out, std::ios::binary);
  o.write(bytes.data(), static_cast<std::streamsize>(h.data_offset));
  for (int c = 0; c < copies; ++c) {
    const unsigned shift = static_cast<unsigned>(c) * (last - first + 1);
    for (std::uint16_t w : words) {
      const std::uint16_t v = w >> 12 == 0x8 ? static_cast<std::uint16_t>(0x8000 | ((w + shift) & 0xFFF)) : w;
      o.write(reinterpret_cast<const char*>(&v), 2);
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path evt3 = fs::path(EDS_SHARED_DATA) / "real/prophesee/evt3_gen41_1280x720.raw";
  if (std::getenv("EDS_BENCH_RECORDINGS") == nullptr && fs::exists(evt3)) {
    const fs::path long_evt3 = longEvt3(evt3, 50);
    benchmark::RegisterBenchmark("evt3_gen41 x50 (one stream)", [long_evt3](benchmark::State& s) {
      readRecording(s, long_evt3);
    })->Unit(benchmark::kMillisecond);
  }
  for (const fs::path& f : recordings())
    benchmark::RegisterBenchmark(f.filename().c_str(), [f](benchmark::State& s) {
      readRecording(s, f);
    })->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
