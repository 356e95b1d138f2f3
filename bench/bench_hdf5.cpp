// Read throughput of Hdf5EventSource on one thread (target: >= 100 M events/s uncompressed).
// Writes its own files first: EDS_BENCH_EVENTS events (default 20 M) in DSEC layout, uncompressed,
// gzip and blosc (when the plugin loads), into a temporary directory removed at the end. The first
// read of each file comes from the page cache, as the writer has just written it.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/events.hpp"
#include "io/hdf5_events.hpp"

namespace {

namespace fs = std::filesystem;
using eds::EventArray;

// DSEC-like: 640x480 at ~2 M events/s, so many events share a microsecond stamp.
EventArray syntheticEvents(std::size_t n) {
  EventArray ev;
  ev.reserve(n);
  std::uint64_t s = 0x9E3779B97F4A7C15ULL;
  eds::TimeNs t = 0;
  for (std::size_t i = 0; i < n; ++i) {
    s ^= s << 13;  // xorshift64: cheap, so that setup stays short
    s ^= s >> 7;
    s ^= s << 17;
    t += 1000 * static_cast<eds::TimeNs>((s >> 40) % 2);
    ev.push_back(t, static_cast<std::uint16_t>((s >> 8) % 640), static_cast<std::uint16_t>((s >> 24) % 480),
                 (s & 1) ? 1 : -1);
  }
  return ev;
}

void readAll(benchmark::State& state, const std::string& path, std::size_t chunk) {
  EventArray buf;
  buf.reserve(chunk);
  std::size_t total = 0;
  for (auto _ : state) {
    eds::Hdf5EventSource src(path, {640, 480});
    std::size_t got = 0;
    do {
      buf.clear();
      got = src.read(buf, chunk);
      benchmark::DoNotOptimize(buf.t.data());
      total += got;
    } while (got > 0);
  }
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(total), benchmark::Counter::kIsRate);
}

// Random seeks followed by a short read: what a player jumping around a sequence does.
void seekAndRead(benchmark::State& state, const std::string& path) {
  eds::Hdf5EventSource src(path);
  const eds::TimeNs t0 = src.firstTimeNs(), span = src.lastTimeNs() - t0 + 1;
  EventArray buf;
  std::uint64_t s = 12345;
  for (auto _ : state) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    src.seek(t0 + static_cast<eds::TimeNs>((s >> 11) % static_cast<std::uint64_t>(span)));
    buf.clear();
    src.read(buf, 1024);
    benchmark::DoNotOptimize(buf.t.data());
  }
  state.counters["seeks/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  const char* env = std::getenv("EDS_BENCH_EVENTS");
  const std::size_t n = env != nullptr ? std::strtoull(env, nullptr, 10) : 20'000'000;
  const fs::path dir = fs::temp_directory_path() / ("eds_bench_hdf5_" + std::to_string(getpid()));
  fs::create_directories(dir);

  const EventArray events = syntheticEvents(n);
  struct Variant {
    const char* name;
    eds::Hdf5Compression compression;
  };
  const Variant variants[] = {{"none", eds::Hdf5Compression::kNone},
                              {"gzip", eds::Hdf5Compression::kGzip},
                              {"blosc", eds::Hdf5Compression::kBloscIfAvailable}};
  for (const Variant& v : variants) {
    const std::string path = (dir / (std::string(v.name) + ".h5")).string();
    const auto start = std::chrono::steady_clock::now();
    const auto used = eds::writeHdf5Events(path, events, 1'600'000'000'000'000, v.compression);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (used != v.compression) {
      std::fprintf(stderr, "blosc plugin unavailable: no blosc benchmark\n");
      fs::remove(path);
      continue;
    }
    std::fprintf(stderr, "wrote %zu events to %s (%.0f MB) in %.1f s\n", n, path.c_str(),
                 static_cast<double>(fs::file_size(path)) / 1e6, secs);
    const std::string base = std::string("BM_Hdf5Read/") + v.name;
    for (const std::size_t chunk : {std::size_t{1} << 16, std::size_t{1} << 20}) {
      benchmark::RegisterBenchmark((base + "/chunk:" + std::to_string(chunk)).c_str(), readAll, path, chunk)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
    benchmark::RegisterBenchmark((std::string("BM_Hdf5Seek/") + v.name).c_str(), seekAndRead, path)
        ->UseRealTime();
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
  return 0;
}
