// Benchmark of the cell-linked neighbour search: ms per rebuild of the full neighbour list for
// 1e5 and 1e6 particles on a jittered square lattice (as fluid particles sit), at re = 2.1 and 4.0 dp,
// one core. Prints a Markdown table for docs/performance.md.
// Run: build/bench/bench_neighbours [n_repeat]
#include "core/geometry.hpp"
#include "core/neighbours.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <string>

using namespace mpsfsi;

int main(int argc, char** argv) {
  const int n_repeat = argc > 1 ? std::max(1, std::stoi(argv[1])) : 5;
  fmt::print("| particles (particle order) | re / dp | list order | neighbours per particle | ms per rebuild (best of {}) | ns per particle | list memory [MiB] |\n", n_repeat);
  fmt::print("|---|---|---|---|---|---|---|\n");
  for (const std::size_t n_target : {100000ul, 1000000ul}) {
    const Real dp = 1.0;
    const int side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n_target))));
    auto x = fill_rectangle(Vec(0, 0), Vec(side * dp, side * dp), dp);
    std::mt19937 rng(1);
    std::uniform_real_distribution<Real> u(-0.1 * dp, 0.1 * dp);
    for (auto& p : x) p += Vec(u(rng), u(rng));
    // Particles in random order (the worst case for memory locality), then in cell order.
    std::shuffle(x.begin(), x.end(), rng);
    for (const bool sorted : {false, true}) {
      if (sorted) {
        const auto order = cell_order(x, 2.0 * dp);  // the grid's cell side for re = 4 dp
        std::vector<Vec> y(x.size());
        for (std::size_t k = 0; k < x.size(); ++k) y[k] = x[static_cast<std::size_t>(order[k])];
        x.swap(y);
      }
      for (const Real factor : {2.1, 4.0}) for (const bool sort_lists : {true, false}) {
        NeighbourList nl;
        CellGrid grid;
        double best = 1e300;
        for (int r = 0; r < n_repeat; ++r) {
          const auto t0 = std::chrono::steady_clock::now();
          build_neighbour_list(x, factor * dp, nl, grid, sort_lists);
          best = std::min(best, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        }
        fmt::print("| {} ({}) | {} | {} | {:.1f} | {:.1f} | {:.0f} | {:.0f} |\n", x.size(), sorted ? "cell order" : "random order",
                   factor, sort_lists ? "sorted" : "cell order", static_cast<double>(nl.n_pairs()) / static_cast<double>(x.size()), best,
                   best * 1e6 / static_cast<double>(x.size()), static_cast<double>(nl.memory_bytes()) / (1 << 20));
      }
    }
  }
  return 0;
}
