// Read throughput of the recording readers on one thread: every event of a file, through the
// Sequence's event source (the format told by content), in 50k-event chunks. The files are the real
// samples in ../shared/data/real, or those listed in EDS_BENCH_RECORDINGS (colon-separated), read
// again and again from the page cache. Reports events per second.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

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

}  // namespace

int main(int argc, char** argv) {
  for (const fs::path& f : recordings())
    benchmark::RegisterBenchmark(f.filename().c_str(), [f](benchmark::State& s) { readRecording(s, f); })
        ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
