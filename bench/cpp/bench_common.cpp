// Microbenchmarks of the shared helpers (checksum throughput bounds tile verification cost).
#include <benchmark/benchmark.h>

#include <vector>

#include "common/checksum.h"

static void BM_Checksum_Tile(benchmark::State& state) {
    std::vector<unsigned char> tile(128 * 128 * 3, 7);
    for (auto _ : state) benchmark::DoNotOptimize(gigascroll::checksum64(tile.data(), tile.size()));
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(tile.size()));
}
BENCHMARK(BM_Checksum_Tile);

BENCHMARK_MAIN();
