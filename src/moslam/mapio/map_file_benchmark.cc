// Loading and saving a map of 500 keyframes of 1000 features (a long indoor run's map): issue 27
// asks for a load under a second. Reports the file's size as a counter.
#include <string>

#include <benchmark/benchmark.h>

#include "moslam/mapio/map_file.h"
#include "moslam/mapio/test_map.h"

namespace moslam::mapio {
namespace {

MapIdentity Identity() {
  MapIdentity id;
  id.sensor = static_cast<int32_t>(io::SensorType::kRgbD);
  id.camera = {525.0, 525.0, 319.5, 239.5, 0.0, 0.0, 0.0, 0.0, 0.0, 40.0};
  id.orb_levels = 8;
  id.orb_scale_factor = 1.2;
  return id;
}

const std::string& MapBytes() {
  static const std::string bytes = [] {
    map::Map map;
    testing::BuildTestMap(500, 1000, 1, &map);
    std::lock_guard<std::mutex> lock(map.mutex());
    return SerializeMap(map, Identity());
  }();
  return bytes;
}

void BM_Load500KeyFrameMap(benchmark::State& state) {
  const std::string& bytes = MapBytes();
  for (auto _ : state) {
    map::Map map;
    std::lock_guard<std::mutex> lock(map.mutex());
    ParseMap(bytes, "bench.map", Identity(), &map);
    benchmark::DoNotOptimize(map.points().size());
  }
  state.counters["file_MB"] = static_cast<double>(bytes.size()) / 1e6;
}
BENCHMARK(BM_Load500KeyFrameMap)->Unit(benchmark::kMillisecond);

void BM_Serialize500KeyFrameMap(benchmark::State& state) {
  map::Map map;
  ParseMap(MapBytes(), "bench.map", Identity(), &map);
  for (auto _ : state) {
    std::lock_guard<std::mutex> lock(map.mutex());
    benchmark::DoNotOptimize(SerializeMap(map, Identity()).size());
  }
}
BENCHMARK(BM_Serialize500KeyFrameMap)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::mapio
