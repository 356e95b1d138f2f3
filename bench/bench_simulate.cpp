// Simulator speed: 10 s of the room preset with the built-in hand-held motion at 240x180, written to
// disk in the ECD layout (events.txt, frames at 25 Hz, depth maps): the acceptance target is < 60 s
// on the 2-core machine.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "sim/presets.hpp"
#include "sim/writer.hpp"

namespace {

void BM_SimulateRoom10s(benchmark::State& state) {
  const auto dir = std::filesystem::temp_directory_path() / "eds_bench_sim";
  std::size_t events = 0;
  for (auto _ : state) {
    const eds::sim::Motion motion(eds::sim::handheldMotion(10.0, 1));
    eds::sim::Scene scene = eds::sim::makePreset("room", motion, 1);
    scene.loadTextures();
    eds::CameraModel cam;
    cam.width = 240, cam.height = 180;
    cam.fx = cam.fy = 199.68;
    cam.cx = 119.5, cam.cy = 89.5;
    eds::sim::SimConfig cfg;
    cfg.render.supersample = 2;
    eds::sim::EcdWriter writer(dir, false, true);
    const auto st = eds::sim::Simulator(scene, cam, motion, cfg).run(motion.start(), motion.end(), writer);
    writer.finish();
    events = st.events;
    state.counters["renders"] = static_cast<double>(st.renders);
  }
  state.counters["events"] = static_cast<double>(events);
  state.counters["Mevents_per_sim_s"] = static_cast<double>(events) / 10.0 * 1e-6;
  std::filesystem::remove_all(dir);
}

BENCHMARK(BM_SimulateRoom10s)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
