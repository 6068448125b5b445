// What the solid shows of itself (SolidSolver, solid/solid_solver_impl.hpp): the output fields refreshed before a
// frame (strain and stress from the bonds, von Mises stress, pressure, displacement, fragment numbers by size),
// the fragment table fragments.csv, and the conserved quantities (SolidDiagnostics).
#include "solid/solid_solver_impl.hpp"

#include "core/collectives.hpp"
#include "core/files.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

namespace mpsfsi {

void SolidSolver::prepare_output(const Real t) {
  Impl& m = *impl_;
  m.compute_fragments();  // (renews owners, ghosts and bonds first)
  m.compute_rotations();
  const std::size_t ns = m.n();
  // Strain tensor eps_i = sym(d/n0_i sum w0/|r0| u_ij (x) e_ij): its trace is eq. 30.
  std::vector<Mat> grad(ns, Mat::Zero());
  m.for_each_intact_bond([&](std::size_t k, std::size_t, std::size_t, std::size_t b, const Vec& r, const Vec& u) {
    grad[k] += m.b_wr[b] * u * (r / r.norm()).transpose();
  });
  // Fragment numbers: labels ordered by size (largest first), ties by label (the fragment's first particle).
  struct Sums {
    Real count = 0, mass = 0;
    Vec mx = Vec::Zero();
    Real body = 0;
  };
  std::map<GlobalId, Sums> local_sums;
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(m.local[k]);
    auto& s = local_sums[static_cast<GlobalId>((*m.f_label)[i])];
    const Real mass = m.material_of(i).mass;
    s.count += 1;
    s.mass += mass;
    s.mx += mass * m.p.position[i];
    s.body = m.p.body[i];
  }
  const int width = 3 + dim + 1;
  std::vector<double> mine;
  for (const auto& [l, s] : local_sums) {
    mine.push_back(static_cast<double>(l));
    mine.push_back(s.count);
    mine.push_back(s.mass);
    for (int a = 0; a < dim; ++a) mine.push_back(s.mx[a]);
    mine.push_back(s.body);
  }
  const std::vector<double> all = m.comm != MPI_COMM_NULL ? all_gather(m.comm, mine) : mine;
  std::map<GlobalId, Sums> sums;
  for (std::size_t q = 0; q < all.size(); q += width) {
    auto& s = sums[static_cast<GlobalId>(all[q])];
    s.count += all[q + 1];
    s.mass += all[q + 2];
    for (int a = 0; a < dim; ++a) s.mx[a] += all[q + 3 + static_cast<std::size_t>(a)];
    s.body = all[q + 3 + dim];
  }
  std::vector<std::pair<GlobalId, Sums>> order(sums.begin(), sums.end());
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.second.count > b.second.count; });
  std::map<GlobalId, int> number;
  for (std::size_t f = 0; f < order.size(); ++f) number[order[f].first] = static_cast<int>(f);
  m.n_frag = order.size();

  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(m.local[k]);
    const Impl::MaterialConstants& mc = m.material_of(i);
    const Mat g = dim * (*m.f_inv_n0)[i] * grad[k];
    const Mat eps = 0.5 * (g + g.transpose());
    const Real tr_eps = eps.trace();
    const Mat sigma = 2 * mc.mu * eps + mc.lambda * tr_eps * Mat::Identity();
#if MPSFSI_DIM == 2
    const Real szz = m.plane_stress ? 0.0 : mc.lambda * tr_eps;  // out of plane: plane stress, plane strain
    const Real shear2 = sigma(0, 1) * sigma(0, 1);
#else
    const Real szz = sigma(2, 2);
    const Real shear2 = sigma(0, 1) * sigma(0, 1) + sigma(0, 2) * sigma(0, 2) + sigma(1, 2) * sigma(1, 2);
#endif
    const Real sxx = sigma(0, 0), syy = sigma(1, 1);
    (*m.f_von_mises)[i] = std::sqrt(0.5 * ((sxx - syy) * (sxx - syy) + (syy - szz) * (syy - szz) + (szz - sxx) * (szz - sxx)) +
                                    3 * shear2);
    (*m.f_pressure)[i] = -mc.lambda * tr_eps;
    (*m.f_displacement)[i] = m.p.position[i] - (*m.f_x0)[i];
    (*m.f_fragment)[i] = number[static_cast<GlobalId>((*m.f_label)[i])];
  }
  const bool writes = m.dist == nullptr || m.dist->rank() == 0;
  if (m.out_dir.empty() || !m.breakable || !writes) return;
  // fragments.csv (bodies that can break): one row per fragment and output time.
  const std::string path = m.out_dir + "/fragments.csv";
  std::ofstream out(path, m.csv_started ? std::ios::app : std::ios::trunc);
  check_written(out, path, "fragment table");
  if (!m.csv_started) out << (dim == 2 ? "time,n_fragments,fragment,body,particles,mass,centroid_x,centroid_y\n"
                                        : "time,n_fragments,fragment,body,particles,mass,centroid_x,centroid_y,centroid_z\n");
  m.csv_started = true;
  for (std::size_t f = 0; f < order.size(); ++f) {
    const auto& s = order[f].second;
    const Vec c = s.mx / s.mass;
    out << fmt::format("{:.9g},{},{},{},{},{:.9g}", t, m.n_frag, f, m.p.bodies[static_cast<std::size_t>(s.body)].name,
                       static_cast<std::size_t>(s.count), s.mass);
    for (int a = 0; a < dim; ++a) out << fmt::format(",{:.9g}", c[a]);
    out << "\n";
  }
  out.flush();
  check_written(out, path, "fragment table");
}

SolidDiagnostics SolidSolver::diagnostics() const {
  Impl& m = *impl_;
  m.sync();
  m.compute_rotations();
  SolidDiagnostics d;
  const std::size_t ns = m.n();
  std::vector<Real> tr(ns, 0);
  // Each bond is seen from both ends: half of its energy at each.
  m.for_each_intact_bond([&](std::size_t k, std::size_t, std::size_t, std::size_t b, const Vec& r, const Vec& u) {
    tr[k] += m.b_vi[b] * u.dot(r) / r.norm();
    d.strain += 0.25 * m.b_k[b] * u.squaredNorm();
  });
  const auto& surface = *m.f_surface;
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(m.local[k]);
    const Impl::MaterialConstants& mc = m.material_of(i);
    const Vec& x = m.p.position[i];
    const Vec& v = m.p.velocity[i];
    const Angular omega = (*m.f_omega)[i];
    d.strain += 0.5 * m.volume * mc.lambda * tr[k] * tr[k];
    d.momentum += mc.mass * v;
    d.angular_momentum += mc.mass * cross(x, v) + mc.inertia * omega;
    d.kinetic += 0.5 * mc.mass * v.squaredNorm();
#if MPSFSI_DIM == 2
    d.rotational += 0.5 * mc.inertia * omega * omega;
#else
    d.rotational += 0.5 * mc.inertia * omega.squaredNorm();
#endif
    // Contact energy: U(d) = k l0 (l0 ln(l0/d) - (l0 - d)) for unbonded surface pairs closer than l0, half at each end.
    if (surface[i] == 0) continue;
    for (const LocalIndex lj : m.local) {
      const auto j = static_cast<std::size_t>(lj);
      if (j == i || surface[j] == 0) continue;
      const Real dist = (m.p.position[j] - x).norm();
      if (dist >= m.dp || m.bonded(k, lj)) continue;
      d.contact += 0.5 * m.k_contact * m.dp * (m.dp * std::log(m.dp / dist) - (m.dp - dist));
    }
  }
  constexpr int n_ang = n_angular;
  constexpr int o = dim + n_ang;
  Real sums[o + 4];
  Real* const ang = angular_data(d.angular_momentum);
  for (int a = 0; a < dim; ++a) sums[a] = d.momentum[a];
  for (int a = 0; a < n_ang; ++a) sums[dim + a] = ang[a];
  sums[o] = d.kinetic;
  sums[o + 1] = d.rotational;
  sums[o + 2] = d.strain;
  sums[o + 3] = d.contact;
  m.allreduce(sums, o + 4, MPI_DOUBLE, MPI_SUM);
  for (int a = 0; a < dim; ++a) d.momentum[a] = sums[a];
  for (int a = 0; a < n_ang; ++a) ang[a] = sums[dim + a];
  d.kinetic = sums[o];
  d.rotational = sums[o + 1];
  d.strain = sums[o + 2];
  d.contact = sums[o + 3];
  return d;
}

}  // namespace mpsfsi
