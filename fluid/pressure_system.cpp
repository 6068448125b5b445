// Splitting a pressure system held whole into the blocks of rows of several ranks (tests, benchmarks).
#include "fluid/pressure_solver.hpp"

#include <algorithm>
#include <cassert>
#include <utility>

namespace mpsfsi {

LocalRows split_system(const LocalRows& whole, const int rank, const int n_ranks) {
  assert(whole.remote_id.empty() && rank >= 0 && rank < n_ranks);
  const std::size_t n = whole.n_rows(), size = static_cast<std::size_t>(n_ranks);
  const std::size_t base = n / size, rem = n % size;
  const auto begin_of = [&](const std::size_t r) { return r * base + std::min(r, rem); };
  const auto rank_of = [&](const std::size_t row) {
    // the block holding `row`: the first rem blocks have base + 1 rows
    const std::size_t long_rows = rem * (base + 1);
    return static_cast<int>(row < long_rows ? row / (base + 1) : rem + (row - long_rows) / std::max<std::size_t>(base, 1));
  };
  const std::size_t r = static_cast<std::size_t>(rank), begin = begin_of(r), end = begin_of(r + 1);
  LocalRows s;
  s.absolute_tolerance = whole.absolute_tolerance;
  s.row_id.assign(whole.row_id.begin() + static_cast<std::ptrdiff_t>(begin), whole.row_id.begin() + static_cast<std::ptrdiff_t>(end));
  s.rhs.assign(whole.rhs.begin() + static_cast<std::ptrdiff_t>(begin), whole.rhs.begin() + static_cast<std::ptrdiff_t>(end));
  // Remote columns numbered in order of the whole system's rows (so by rank, then row), after the own rows;
  // each row's columns are sorted by local id (the LocalRows contract).
  std::vector<LocalIndex> local_of(n, -1);
  const LocalIndex n_own = static_cast<LocalIndex>(end - begin);
  for (std::size_t i = begin; i < end; ++i)
    for (std::size_t k = whole.row_ptr[i]; k < whole.row_ptr[i + 1]; ++k) {
      const auto c = static_cast<std::size_t>(whole.col[k]);
      if ((c < begin || c >= end) && local_of[c] < 0) local_of[c] = 0;
    }
  for (std::size_t c = 0; c < n; ++c)
    if (c >= begin && c < end) {
      local_of[c] = static_cast<LocalIndex>(c - begin);
    } else if (local_of[c] == 0) {
      local_of[c] = n_own + static_cast<LocalIndex>(s.remote_id.size());
      s.remote_id.push_back(whole.row_id[c]);
      s.remote_rank.push_back(rank_of(c));
    }
  if (!whole.group.empty()) {  // the groups of the own rows, then of the remote columns, cut by the blocks
    const auto key = [&](const std::size_t c) { return (static_cast<std::int64_t>(rank_of(c)) << 44) + whole.group[c]; };
    for (std::size_t c = begin; c < end; ++c) s.group.push_back(key(c));
    for (std::size_t c = 0; c < n; ++c)
      if (local_of[c] >= n_own) s.group.push_back(key(c));
  }
  s.row_ptr.assign(1, 0);
  std::vector<std::pair<LocalIndex, Real>> row;
  for (std::size_t i = begin; i < end; ++i) {
    row.clear();
    for (std::size_t k = whole.row_ptr[i]; k < whole.row_ptr[i + 1]; ++k)
      row.emplace_back(local_of[static_cast<std::size_t>(whole.col[k])], whole.value[k]);
    std::stable_sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [c, v] : row) {
      s.col.push_back(c);
      s.value.push_back(v);
    }
    s.row_ptr.push_back(s.col.size());
  }
  return s;
}

}  // namespace mpsfsi
