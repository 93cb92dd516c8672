// Merged page-table layout (VT-mobile-VR §3.2): the paintings' level-0 page tables, each a
// power-of-two Mp x Np grid, are packed into one power-of-two Mc x Nc table. Every table sits
// at an offset that is a multiple of its own size, so at page-table level l <= log2(min(Mp, Np))
// its region is exactly (Mp >> l) x (Np >> l) entries at (x >> l, y >> l) and regions never
// overlap: eqs (5, 6) stay exact at every level.
//
// Two packers: a shelf packer (the baseline) and a BRKGA (biased random-key genetic algorithm,
// Goncalves & Resende 2013). A BRKGA chromosome is 2n + 1 keys in [0, 1): the first n sorted
// give the placement order, the next n choose each table's placement rule (bottom-left or
// left-bottom over aligned corner positions), the last one the strip width.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace gigascroll {

struct TableSize {
    std::uint32_t width, height;  // powers of two
};

struct PageLayout {
    std::uint32_t width = 0, height = 0;  // merged table, powers of two
    std::vector<std::pair<std::uint32_t, std::uint32_t>> offsets;
    double fill_ratio = 0;                // sum of table areas / merged area
};

struct BrkgaOptions {
    std::uint32_t population = 0;   // 0: chosen from the problem size
    std::uint32_t generations = 300;
    std::uint32_t stall_generations = 60;  // stop after this many without improvement
    double elite_fraction = 0.2;
    double mutant_fraction = 0.15;
    double rho_e = 0.7;             // probability a child inherits the elite parent's key
    std::uint64_t seed = 0;
    unsigned threads = 0;
    // Overlap tests in all decodes (deterministic, about 1e9 a second): bounds the time with
    // thousands of tables, where the population and then the generations shrink to fit.
    std::uint64_t work_budget = 3'000'000'000;
};

PageLayout shelf_layout(const std::vector<TableSize>& tables);

// The layout a pack build uses: both packers run (their fill ratios go into the manifest) and
// `method` ("brkga" or "shelf", InvalidArgument otherwise) picks the one whose offsets are
// used; the chosen layout is checked.
struct PlannedLayout {
    PageLayout chosen, shelf, brkga;
};
PlannedLayout plan_layout(const std::vector<TableSize>& tables, const std::string& method,
                          std::uint64_t seed);
PageLayout brkga_layout(const std::vector<TableSize>& tables, const BrkgaOptions& options = {});

// InvalidArgument unless every table is a power of two, aligned to its size, inside the merged
// power-of-two table, and no two overlap.
void check_layout(const std::vector<TableSize>& tables, const PageLayout& layout);

}  // namespace gigascroll
