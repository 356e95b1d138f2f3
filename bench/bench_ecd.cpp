// Throughput of the ECD text event reader, plain and gzip. Writes its own test files first
// (ECD-style lines "t x y p" with 9 decimals), then reads them back on one thread.
#include <benchmark/benchmark.h>
#include <zlib.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "io/ecd_events.hpp"

namespace {

namespace fs = std::filesystem;
constexpr std::size_t kEvents = 4'000'000;

const fs::path& benchDir() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / "eds_bench_ecd";
    fs::create_directories(d);
    const fs::path txt = d / "events.txt", gz = d / "events.txt.gz";
    if (!fs::exists(txt) || !fs::exists(gz)) {
      std::mt19937 rng(1);
      std::uniform_int_distribution<int> ux(0, 239), uy(0, 179), up(0, 1);
      std::string all;
      all.reserve(kEvents * 24);
      char line[64];
      for (std::size_t i = 0; i < kEvents; ++i) {
        const double t = 0.02 + i * 1.25e-6;  // 0.8 M events/s, like the ESIM sequence
        const int n = std::snprintf(line, sizeof line, "%.9f %d %d %d\n", t, ux(rng), uy(rng), up(rng));
        all.append(line, n);
      }
      std::FILE* f = std::fopen(txt.c_str(), "wb");
      std::fwrite(all.data(), 1, all.size(), f);
      std::fclose(f);
      gzFile g = gzopen(gz.c_str(), "wb6");
      gzwrite(g, all.data(), static_cast<unsigned>(all.size()));
      gzclose(g);
    }
    return d;
  }();
  return dir;
}

void readAll(benchmark::State& state, const char* name) {
  const fs::path file = benchDir() / name;
  std::size_t total = 0;
  eds::EventArray chunk;
  chunk.reserve(1 << 16);
  for (auto _ : state) {
    eds::EcdEventSource src(file, {240, 180});
    std::size_t n = 0;
    while (true) {
      chunk.clear();
      const std::size_t got = src.read(chunk, 1 << 16);
      if (got == 0) break;
      n += got;
    }
    benchmark::DoNotOptimize(n);
    total += n;
  }
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(total), benchmark::Counter::kIsRate);
}

void BM_EcdTextPlain(benchmark::State& state) { readAll(state, "events.txt"); }
void BM_EcdTextGzip(benchmark::State& state) { readAll(state, "events.txt.gz"); }

// zlib's inflate alone, as the floor for the gzip reader.
void BM_GzipInflateOnly(benchmark::State& state) {
  const fs::path file = benchDir() / "events.txt.gz";
  std::vector<char> buf(1 << 20);
  for (auto _ : state) {
    gzFile g = gzopen(file.c_str(), "rb");
    gzbuffer(g, 1 << 18);
    while (gzread(g, buf.data(), static_cast<unsigned>(buf.size())) > 0) {
    }
    gzclose(g);
  }
  state.counters["events/s"] =
      benchmark::Counter(static_cast<double>(kEvents * state.iterations()), benchmark::Counter::kIsRate);
}

BENCHMARK(BM_EcdTextPlain)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_EcdTextGzip)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GzipInflateOnly)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
