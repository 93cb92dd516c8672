#include "pack/page_layout.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>
#include <string>

#include "common/bits.h"
#include "common/error.h"
#include "common/parallel.h"
#include "pack/geometry.h"

namespace gigascroll {
namespace {

struct Rect {
    std::uint64_t x, y, w, h;
};

bool overlaps(const Rect& a, const Rect& b) {
    return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

std::uint64_t round_up(std::uint64_t v, std::uint64_t m) { return (v + m - 1) / m * m; }

void check_tables(const std::vector<TableSize>& tables) {
    require(!tables.empty(), "no page tables to lay out");
    for (const auto& t : tables)
        require(t.width >= 1 && t.height >= 1 && is_pow2(t.width) && is_pow2(t.height),
                "page-table sizes must be powers of two");
}

PageLayout finish_layout(const std::vector<TableSize>& tables, const std::vector<Rect>& placed) {
    PageLayout out;
    std::uint64_t mx = 1, my = 1, area = 0;
    out.offsets.resize(tables.size());
    for (std::size_t i = 0; i < tables.size(); ++i) {
        mx = std::max(mx, placed[i].x + placed[i].w);
        my = std::max(my, placed[i].y + placed[i].h);
        area += placed[i].w * placed[i].h;
        out.offsets[i] = {static_cast<std::uint32_t>(placed[i].x), static_cast<std::uint32_t>(placed[i].y)};
    }
    require(mx <= (1u << 31) && my <= (1u << 31), "merged page table too large");
    out.width = next_pow2(static_cast<std::uint32_t>(mx));
    out.height = next_pow2(static_cast<std::uint32_t>(my));
    out.fill_ratio = double(area) / (double(out.width) * out.height);
    return out;
}

// Strip widths worth trying: powers of two from the widest table to the sum of widths.
std::vector<std::uint64_t> strip_widths(const std::vector<TableSize>& tables) {
    std::uint64_t wmax = 0, wsum = 0;
    for (const auto& t : tables) {
        wmax = std::max<std::uint64_t>(wmax, t.width);
        wsum += t.width;
    }
    std::vector<std::uint64_t> widths;
    for (std::uint64_t w = wmax; w < 2 * wsum && w <= (1u << 31); w *= 2) widths.push_back(w);
    return widths;
}

// (power-of-two area, bounding-box area): smaller is better, lexicographically.
using Cost = std::pair<double, double>;

Cost cost_of(const std::vector<Rect>& placed) {
    std::uint64_t mx = 1, my = 1;
    for (const auto& r : placed) {
        mx = std::max(mx, r.x + r.w);
        my = std::max(my, r.y + r.h);
    }
    return {double(next_pow2(mx)) * double(next_pow2(my)), double(mx) * double(my)};
}

// Places tables in `order`, each with rule[i] (false: bottom-left, true: left-bottom), at the
// best aligned candidate corner inside a strip of width `strip`.
//
// Speed (2000 paintings must lay out in seconds): every table is a power of two aligned to its
// own size, so on a grid of cells as large as the largest table each table lies in exactly one
// cell and only that cell's tables can overlap it; a corner covered by a placed table is dropped
// (any position from it slides up past that table anyway).
std::vector<Rect> place(const std::vector<TableSize>& tables, const std::vector<std::uint32_t>& order,
                        const std::vector<bool>& left_first, std::uint64_t strip,
                        std::uint64_t* work = nullptr) {
    std::uint64_t tests = 0;  // overlap tests: the decode's cost, for the GA's work budget
    std::uint64_t cell_w = 1, cell_h = 1;
    for (const auto& t : tables) {
        cell_w = std::max<std::uint64_t>(cell_w, t.width);
        cell_h = std::max<std::uint64_t>(cell_h, t.height);
    }
    const std::uint64_t grid_w = std::max<std::uint64_t>(1, strip / cell_w);
    std::vector<std::vector<Rect>> cells;  // row-major, rows added as the packing grows
    auto cell_of = [&](const Rect& r) -> std::vector<Rect>* {
        const std::uint64_t k = (r.y / cell_h) * grid_w + r.x / cell_w;
        return k < cells.size() ? &cells[k] : nullptr;
    };
    std::vector<Rect> placed(tables.size());
    std::vector<std::pair<std::uint64_t, std::uint64_t>> corners{{0, 0}}, kept;
    for (std::uint32_t i : order) {
        const std::uint64_t w = tables[i].width, h = tables[i].height;
        bool found = false;  // corner (0, 0) always yields a position: strip >= widest table
        Rect best{0, 0, w, h};
        for (const auto& [cx, cy] : corners) {
            Rect r{round_up(cx, w), round_up(cy, h), w, h};
            if (r.x + w > strip) continue;
            if (found && (left_first[i] ? r.x > best.x : r.y > best.y)) continue;  // cannot win
            // Slide up past blockers (keeps alignment), so every corner yields a position.
            for (bool moved = true; moved;) {
                moved = false;
                if (const auto* blockers = cell_of(r))
                    for (const Rect& o : *blockers)
                        if (++tests, overlaps(r, o)) {
                            r.y = round_up(o.y + o.h, h);
                            moved = true;
                            break;
                        }
            }
            const bool better =
                !found || (left_first[i] ? (r.x < best.x || (r.x == best.x && r.y < best.y))
                                         : (r.y < best.y || (r.y == best.y && r.x < best.x)));
            if (better) {
                best = r;
                found = true;
            }
        }
        const std::uint64_t k = (best.y / cell_h) * grid_w + best.x / cell_w;
        if (k >= cells.size()) cells.resize((k / grid_w + 1) * grid_w);
        cells[k].push_back(best);
        placed[i] = best;
        kept.clear();
        for (const auto& c : corners)
            if (!(c.first >= best.x && c.first < best.x + w && c.second >= best.y &&
                  c.second < best.y + h))
                kept.push_back(c);
        corners.swap(kept);
        if (best.x + w < strip) corners.emplace_back(best.x + w, best.y);
        corners.emplace_back(best.x, best.y + h);
    }
    if (work) *work = tests + corners.size();
    return placed;
}

}  // namespace

void check_layout(const std::vector<TableSize>& tables, const PageLayout& layout) {
    check_tables(tables);
    require(layout.offsets.size() == tables.size(), "layout has the wrong number of offsets");
    require(is_pow2(layout.width) && is_pow2(layout.height),
            "merged page table must be a power of two in each dimension");
    std::vector<Rect> r;
    for (std::size_t i = 0; i < tables.size(); ++i) {
        const auto [x, y] = layout.offsets[i];
        const auto& t = tables[i];
        require(x % t.width == 0 && y % t.height == 0,
                "page table " + std::to_string(i) + " is not aligned to its size");
        require(std::uint64_t(x) + t.width <= layout.width &&
                    std::uint64_t(y) + t.height <= layout.height,
                "page table " + std::to_string(i) + " lies outside the merged table");
        const Rect ri{x, y, t.width, t.height};
        for (std::size_t j = 0; j < r.size(); ++j)
            require(!overlaps(ri, r[j]), "page tables " + std::to_string(j) + " and " +
                                             std::to_string(i) + " overlap");
        r.push_back(ri);
    }
}

PageLayout shelf_layout(const std::vector<TableSize>& tables) {
    check_tables(tables);
    std::vector<std::uint32_t> order(tables.size());
    std::iota(order.begin(), order.end(), 0u);
    // Tallest first: every shelf's y is then a multiple of every later table's height.
    std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) {
        return tables[a].height != tables[b].height ? tables[a].height > tables[b].height
                                                    : tables[a].width > tables[b].width;
    });
    PageLayout best;
    Cost best_cost{std::numeric_limits<double>::infinity(), 0};
    for (std::uint64_t strip : strip_widths(tables)) {
        std::vector<Rect> placed(tables.size());
        std::uint64_t x = 0, y = 0, shelf_h = 0;
        for (std::uint32_t i : order) {
            const std::uint64_t w = tables[i].width, h = tables[i].height;
            std::uint64_t px = round_up(x, w);
            if (px + w > strip) {
                y += shelf_h;
                shelf_h = 0;
                px = 0;
            }
            if (shelf_h == 0) shelf_h = h;
            placed[i] = Rect{px, y, w, h};
            x = px + w;
        }
        const Cost c = cost_of(placed);
        if (c < best_cost) {
            best_cost = c;
            best = finish_layout(tables, placed);
        }
    }
    return best;
}

PlannedLayout plan_layout(const std::vector<TableSize>& tables, const std::string& method,
                          std::uint64_t seed) {
    require(method == "brkga" || method == "shelf",
            "unknown layout method '" + method + "' (expected brkga or shelf)");
    PlannedLayout p;
    p.shelf = shelf_layout(tables);
    if (method == "brkga") {  // the shelf layout alone does not need the GA (its width stays 0)
        BrkgaOptions o;
        o.seed = seed;
        p.brkga = brkga_layout(tables, o);
    }
    p.chosen = method == "shelf" ? p.shelf : p.brkga;
    check_layout(tables, p.chosen);
    return p;
}

PageLayout brkga_layout(const std::vector<TableSize>& tables, const BrkgaOptions& o) {
    check_tables(tables);
    require(o.elite_fraction > 0 && o.elite_fraction < 1 && o.mutant_fraction >= 0 &&
                o.elite_fraction + o.mutant_fraction < 1 && o.rho_e > 0.5 && o.rho_e < 1,
            "BRKGA parameters out of range");
    const std::size_t n = tables.size();
    const std::vector<std::uint64_t> widths = strip_widths(tables);
    const std::size_t genes = 2 * n + 1;

    // Lower bound on the merged area: stop as soon as it is reached.
    std::uint64_t area = 0, wmax = 0, hmax = 0;
    for (const auto& t : tables) {
        area += std::uint64_t(t.width) * t.height;
        wmax = std::max<std::uint64_t>(wmax, t.width);
        hmax = std::max<std::uint64_t>(hmax, t.height);
    }
    const double bound = double(std::max(next_pow2(area), wmax * hmax));

    auto decode = [&](const std::vector<double>& keys, std::uint64_t* work = nullptr) {
        std::vector<std::uint32_t> order(n);
        std::iota(order.begin(), order.end(), 0u);
        std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) { return keys[a] < keys[b]; });
        std::vector<bool> left(n);
        for (std::size_t i = 0; i < n; ++i) left[i] = keys[n + i] >= 0.5;
        const std::size_t wi = std::min(widths.size() - 1, std::size_t(keys[2 * n] * widths.size()));
        return place(tables, order, left, widths[wi], work);
    };

    // Seed one chromosome with the shelf order (tallest first, bottom-left) so the GA starts
    // no worse than a greedy heuristic. Its decode also measures what one decode costs.
    std::vector<double> seeded(genes, 0.0);
    {
        std::vector<std::uint32_t> order(n);
        std::iota(order.begin(), order.end(), 0u);
        std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) {
            return tables[a].height != tables[b].height ? tables[a].height > tables[b].height
                                                        : tables[a].width > tables[b].width;
        });
        for (std::size_t r = 0; r < n; ++r) seeded[order[r]] = (r + 0.5) / n;
        for (std::size_t i = 0; i < n; ++i) seeded[n + i] = 0.25;
    }
    std::uint64_t decode_work = 0;
    const std::vector<Rect> seeded_placed = decode(seeded, &decode_work);
    // Work budget (overlap tests, so deterministic; ~1e9 a second): with thousands of tables
    // a decode is expensive, and the population (then the generations) shrink to fit.
    const std::uint64_t budget = o.work_budget;
    const std::uint64_t affordable = budget / std::max<std::uint64_t>(1, decode_work);
    const std::size_t pop = o.population ? o.population
                                         : std::min<std::size_t>(std::clamp<std::size_t>(10 * genes, 40, 200),
                                                                 std::size_t(affordable / 4));
    const std::size_t n_elite = std::max<std::size_t>(1, std::size_t(o.elite_fraction * pop));
    const std::size_t n_mutant = std::size_t(o.mutant_fraction * pop);
    auto best_of_shelf = [&](PageLayout out) {
        // Never worse than the baseline (the GA's start need not contain the shelf layout).
        PageLayout shelf = shelf_layout(tables);
        return double(shelf.width) * shelf.height < double(out.width) * out.height ? shelf : out;
    };
    if (pop < 8 || cost_of(seeded_placed).first <= bound)  // no room for a GA, or optimal already
        return best_of_shelf(finish_layout(tables, seeded_placed));

    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    std::vector<std::vector<double>> population(pop, std::vector<double>(genes));
    for (auto& c : population)
        for (auto& k : c) k = U(rng);
    population[0] = seeded;
    std::vector<Cost> cost(pop);
    std::vector<std::uint64_t> work(pop);
    std::uint64_t used = decode_work, last_generation = 0;
    auto evaluate = [&](std::size_t from) {
        parallel_for(pop - from, 4, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = from + b; i < from + e; ++i)
                cost[i] = cost_of(decode(population[i], &work[i]));
        }, o.threads);
        last_generation = 0;
        for (std::size_t i = from; i < pop; ++i) last_generation += work[i];
        used += last_generation;
    };
    evaluate(0);
    std::vector<std::size_t> rank(pop);
    auto sort_population = [&] {
        std::iota(rank.begin(), rank.end(), std::size_t(0));
        std::stable_sort(rank.begin(), rank.end(), [&](auto a, auto b) { return cost[a] < cost[b]; });
        std::vector<std::vector<double>> p2(pop);
        std::vector<Cost> c2(pop);
        for (std::size_t i = 0; i < pop; ++i) {
            p2[i] = std::move(population[rank[i]]);
            c2[i] = cost[rank[i]];
        }
        population.swap(p2);
        cost.swap(c2);
    };
    sort_population();
    Cost best = cost[0];
    std::uint32_t stall = 0;
    for (std::uint32_t gen = 0; gen < o.generations && best.first > bound && stall < o.stall_generations &&
                            used + last_generation <= budget; ++gen) {
        // Elites survive; mutants are fresh random keys; the rest are biased crossovers of an
        // elite and a non-elite parent, taking each key from the elite with probability rho_e.
        std::vector<std::vector<double>> next(pop, std::vector<double>(genes));
        std::vector<Cost> next_cost(pop);
        for (std::size_t i = 0; i < n_elite; ++i) {
            next[i] = population[i];
            next_cost[i] = cost[i];
        }
        std::uniform_int_distribution<std::size_t> pick_elite(0, n_elite - 1);
        std::uniform_int_distribution<std::size_t> pick_other(n_elite, pop - 1);
        for (std::size_t i = n_elite; i < pop - n_mutant; ++i) {
            const auto& a = population[pick_elite(rng)];
            const auto& b = population[pick_other(rng)];
            for (std::size_t k = 0; k < genes; ++k) next[i][k] = U(rng) < o.rho_e ? a[k] : b[k];
        }
        for (std::size_t i = pop - n_mutant; i < pop; ++i)
            for (auto& k : next[i]) k = U(rng);
        population.swap(next);
        cost.swap(next_cost);
        evaluate(n_elite);
        sort_population();
        if (cost[0] < best) {
            best = cost[0];
            stall = 0;
        } else {
            ++stall;
        }
    }
    return best_of_shelf(finish_layout(tables, decode(population[0])));
}

}  // namespace gigascroll
