// Between the solid's fragments (SolidSolver::Impl, solid/solid_solver_impl.hpp): the contact of unbonded surface
// particles (seed 004 §4.4; bodies and the fragments of broken bonds) and the fragment labels, the connected
// components of the intact bonds.
#include "solid/solid_solver_impl.hpp"

#include "core/text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace mpsfsi {

namespace internal = solid_detail::internal;

void SolidSolver::Impl::contact_forces(std::size_t& n_contacts) {
  // Surface flags as of the start of the step (the ghosts' from the exchange), so that every rank count
  // sees the same pairs.
  const auto& surface = *f_surface;
  s_x.clear();
  s_i.clear();
  for (const LocalIndex li : local) {
    if (surface[static_cast<std::size_t>(li)] == 0) continue;
    s_x.push_back(p.position[static_cast<std::size_t>(li)]);
    s_i.push_back(li);
  }
  std::string error;
  if (s_x.size() >= 2) {
    // Guard the cell grid: a blown-up state (dt too large) would ask for an absurd number of cells.
    Vec lo = s_x[0], hi = s_x[0];
    bool finite = true;
    for (const Vec& y : s_x) {
      finite = finite && y.allFinite();
      lo = lo.cwiseMin(y);
      hi = hi.cwiseMax(y);
    }
    const Vec cells = (hi - lo) / dp + Vec::Ones();
    if (!finite)
      error = "solid: a surface particle has a non-finite position; the run went unstable (reduce dt)";
    else if (cells.prod() > 16.0 * static_cast<Real>(s_x.size()) + 4e6)
      error = fmt::format(
          "solid: the surface particles spread over a box of sides {} m ({:.3g} contact cells of side dp for {} particles); "
          "the run went unstable (reduce dt) or fragments flew too far apart (shrink the domain)",
          show_point(hi - lo), cells.prod(), s_x.size());
  }
  if (!error.empty()) throw std::runtime_error(error);
  if (s_x.size() < 2) return;
  build_neighbour_list(s_x, dp, s_nl, s_grid);
  const Real d_min = 0.05 * dp;
  // The owned surface particles come first in s_i, in order of k.
  std::size_t k = 0;
  for (std::size_t q = 0; q < s_x.size(); ++q) {
    const auto i = static_cast<std::size_t>(s_i[q]);
    if (i >= p.n_owned()) break;
    while (static_cast<std::size_t>(local[k]) != i) ++k;
    s_pairs.clear();
    for (std::size_t e = s_nl.begin(q); e < s_nl.end(q); ++e) {
      const LocalIndex j = s_i[static_cast<std::size_t>(s_nl.index[e])];
      if (bonded(k, j)) continue;  // adjacent on one surface
      s_pairs.emplace_back(p.global_id[static_cast<std::size_t>(j)], j);
    }
    std::sort(s_pairs.begin(), s_pairs.end());  // the same sum in the same order on any rank count
    for (const auto& [gj, jl] : s_pairs) {
      const auto j = static_cast<std::size_t>(jl);
      // Pair in order of global id (a, b): both ends compute the same force.
      const bool i_first = p.global_id[i] < gj;
      const std::size_t a = i_first ? i : j, c = i_first ? j : i;
      const Vec r = p.position[c] - p.position[a];
      const Real d = r.norm();
      // Direction: along r; for coincident particles fall back to the reference direction.
      Vec e = d > 1e-12 * dp ? Vec(r / d) : Vec((*f_x0)[c] - (*f_x0)[a]);
      if (d <= 1e-12 * dp) e = e.norm() > 0 ? Vec(e.normalized()) : Vec(Vec::UnitX());
      // Repulsion k (l0 - d) l0/d: linear near contact, stiffening without bound as d -> 0.
      const Real mag = k_contact * (dp - d) * dp / std::max(d, d_min);
      force[k] -= (i_first ? mag : -mag) * e;
      if (i_first) ++n_contacts;
    }
  }
}

void SolidSolver::Impl::compute_fragments() {
  // Connected components of the intact bonds: union-find over this rank's particles, labels = smallest
  // global id of a component; across ranks the ghosts' labels are exchanged until no label changes.
  sync();
  const std::size_t nl = p.size();
  std::vector<std::size_t> parent(nl);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](std::size_t a) {
    while (parent[a] != a) {
      parent[a] = parent[parent[a]];
      a = parent[a];
    }
    return a;
  };
  for (std::size_t k = 0; k < n(); ++k)
    for (std::size_t b = b_off[k]; b < b_off[k + 1]; ++b) {
      if (!b_intact[b]) continue;
      const std::size_t ra = find(static_cast<std::size_t>(local[k])), rb = find(static_cast<std::size_t>(b_j[b]));
      if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
    }
  auto& label = *f_label;
  std::vector<GlobalId> root_label(nl, std::numeric_limits<GlobalId>::max());
  for (const LocalIndex li : local) {
    const auto i = static_cast<std::size_t>(li);
    auto& l = root_label[find(i)];
    l = std::min(l, p.global_id[i]);
  }
  for (int round = 0;; ++round) {
    for (std::size_t k = 0; k < n(); ++k) {
      const auto i = static_cast<std::size_t>(local[k]);
      label[i] = static_cast<Real>(root_label[find(i)]);
    }
    if (n_ranks() == 1) break;
    exchange({internal::label});
    int changed = 0;
    for (const LocalIndex li : local) {
      const auto i = static_cast<std::size_t>(li);
      if (i < p.n_owned()) continue;
      auto& l = root_label[find(i)];
      const auto g = static_cast<GlobalId>(label[i]);
      if (g < l) {
        l = g;
        changed = 1;
      }
    }
    allreduce(&changed, 1, MPI_INT, MPI_MAX);
    if (!changed) break;
    if (round > 100000) throw std::logic_error("solid: the fragment labels do not settle");
  }
  // Each fragment has one particle whose global id is its label.
  unsigned long long n_roots = 0;
  for (std::size_t k = 0; k < n(); ++k) {
    const auto i = static_cast<std::size_t>(local[k]);
    n_roots += static_cast<GlobalId>(label[i]) == p.global_id[i];
  }
  allreduce(&n_roots, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM);
  n_frag = n_roots;
}

std::size_t SolidSolver::n_fragments() const { return impl_->n_frag; }

Real SolidSolver::min_distance_between_fragments() const {
  Impl& m = *impl_;
  m.compute_fragments();
  const auto& label = *m.f_label;
  std::vector<Vec> x;
  for (const LocalIndex li : m.local) x.push_back(m.p.position[static_cast<std::size_t>(li)]);
  NeighbourList nl;
  build_neighbour_list(x, m.dp, nl);
  Real best = std::numeric_limits<Real>::infinity();
  for (std::size_t k = 0; k < m.n(); ++k) {  // row k: owned particle k
    const auto i = static_cast<std::size_t>(m.local[k]);
    for (std::size_t q = nl.begin(k); q < nl.end(k); ++q) {
      const auto j = static_cast<std::size_t>(m.local[static_cast<std::size_t>(nl.index[q])]);
      if (label[i] != label[j]) best = std::min(best, (x[static_cast<std::size_t>(nl.index[q])] - x[k]).norm());
    }
  }
  m.allreduce(&best, 1, MPI_DOUBLE, MPI_MIN);
  return best;
}

}  // namespace mpsfsi
