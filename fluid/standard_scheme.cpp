// The standard pressure scheme (fluid.scheme = standard; fluid/fluid_parameters.hpp FluidScheme): the PPE of
// seed 004 eq. 23 with weak compressibility and relaxation (the alpha term enters the matrix as 1 / (c^2 dt^2),
// docs/architecture.md, ## Numerical choices), and the correction (eq. 19, 24) with the minimum-pressure gradient
// (eq. 9 with p_min) or the corrected gradient (eq. 14-15).
#include "fluid/pressure_scheme.hpp"

#include "core/buffers.hpp"
#include "core/operators.hpp"

#include <limits>

namespace mpsfsi::fluid_detail {

namespace {

class StandardScheme final : public PressureScheme {
 public:
  StandardScheme(FluidCore& fluid_core, const FluidParameters& fluid)
      : core(fluid_core), p(core.p), re_g(core.re_g), re_l(core.re_l), lat_g(core.lat_g), lat_l(core.lat_l),
        rho(core.rho), c(core.c), kappa(core.kappa), roles(core.roles), nl(core.nl), near(core.near), n_star(core.n_star),
        dv(core.dv), row_of(core.row_of), particle_of_row(core.particle_of_row), sys(core.sys),
        corrected(fluid.gradient == PressureGradient::corrected) {}

  Real near_radius() const override { return re_g; }
  bool ghost_needs_row(Role) const override { return false; }
  bool rows_need_wide_list() const override { return true; }  // eq. 23's Laplacian at re_laplacian

  /// Eq. 23 assembled for this rank's rows (its owned particles with a pressure unknown): -lap P + P / (c^2
  /// dt^2) = kappa rho / dt^2 (n* - n0) / n0, with p = 0 rows (free surface) as identity rows dropped from
  /// the other rows' columns (keeps symmetry). Ghosts with a pressure unknown are the remote columns.
  void assemble(const Real dt) override {
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::size_t n_rows = particle_of_row.size();
    // Upper bound of the entries: each row's neighbours plus its diagonal; trimmed at the end.
    std::size_t max_entries = 0;
    for (std::size_t r = 0; r < n_rows; ++r) max_entries += nl.count(static_cast<std::size_t>(particle_of_row[r])) + 1;
    resize_with_headroom(sys.col, max_entries);
    resize_with_headroom(sys.value, max_entries);
    std::size_t m = 0;  // entries written
    sys.row_ptr[0] = 0;
    const Real a = 2.0 * dim / (lat_l.lambda * lat_l.n0);
    const Real compress = 1.0 / (c * c * dt * dt);
    const Real source = kappa * rho / (dt * dt) / lat_g.n0;
    const Real dirichlet_diag = a * lat_l.n0 + compress;
    const auto is_row = [&](const std::size_t j) { return has_row(roles[j]); };
    for (std::size_t r = 0; r < n_rows; ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      const auto me = static_cast<LocalIndex>(r);
      if (surface[i] != 0) {
        sys.col[m] = me;
        sys.value[m++] = dirichlet_diag;
        sys.rhs[r] = 0;
        sys.row_ptr[r + 1] = m;
        continue;
      }
      Real diag = compress;
      std::size_t diag_pos = std::numeric_limits<std::size_t>::max();
      // Row i of eq. 12's Laplacian (pair weights a w_ij) over the neighbours with pressure rows; the list is
      // sorted by local index and row_of increases with it, so the columns come out sorted.
      for_each_pair(p.position, nl, re_l, i, is_row, [&](const std::size_t j, const Vec&, Real, const Real w) {
        const Real coef = a * w;
        diag += coef;
        if (surface[j] != 0) return;
        if (diag_pos == std::numeric_limits<std::size_t>::max() && j > i) {
          diag_pos = m;
          sys.col[m] = me;
          sys.value[m++] = 0;
        }
        sys.col[m] = row_of[j];
        sys.value[m++] = -coef;
      });
      if (diag_pos == std::numeric_limits<std::size_t>::max()) {
        diag_pos = m;
        sys.col[m] = me;
        sys.value[m++] = 0;
      }
      sys.value[diag_pos] = diag;
      sys.rhs[r] = source * (n_star[i] - lat_g.n0);
      sys.row_ptr[r + 1] = m;
    }
    sys.col.resize(m);
    sys.value.resize(m);
  }

  /// Eq. 19 and 24: v += -dt/rho grad P, r += dt (-dt/rho grad P). grad P by eq. 9 with p_min (every pair
  /// repels), or by the corrected gradient eq. 14-15 (falls back to p_min where the matrix is singular).
  void correct(const Real dt) override {
    const auto& pressure = p.scalar_field(fluid_fields::pressure);
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::size_t n = p.n_owned();
    const Real c_grad = dim / lat_g.n0;
    dv.resize(n);  // n: the owned particles
    const auto is_row = [&](const std::size_t j) { return has_row(roles[j]); };
    for (std::size_t i = 0; i < n; ++i) {
      dv[i].setZero();
      if (roles[i] != Role::fluid) continue;
      if (corrected && surface[i] == 0) {
        // Eq. 14-15 where A_i is well conditioned (det A > 1e-2 tr(A)^d), else the p_min gradient below.
        const CorrectedGradient c = corrected_gradient_at(p.position, near, re_g, i, pressure, 1e-2, is_row);
        if (c.ok) {
          dv[i] = -dt / rho * c.gradient;
          continue;
        }
      }
      const Real p_min = min_value_at(p.position, near, re_g, i, pressure, is_row);
      dv[i] = -dt / rho * c_grad * gradient_sum_at(p.position, near, re_g, i, pressure, p_min, is_row);
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (roles[i] != Role::fluid) continue;
      p.velocity[i] += dv[i];
      p.position[i] += dt * dv[i];
    }
  }

 private:
  FluidCore& core;
  // The core's state under the names the scheme's formulas use.
  ParticleSet& p;
  const Real& re_g;
  const Real& re_l;
  const LatticeConstants& lat_g;
  const LatticeConstants& lat_l;
  const Real& rho;
  const Real& c;
  const Real& kappa;
  const std::vector<Role>& roles;
  NeighbourList& nl;
  NeighbourList& near;
  std::vector<Real>& n_star;
  std::vector<Vec>& dv;
  std::vector<LocalIndex>& row_of;
  std::vector<LocalIndex>& particle_of_row;
  LocalRows& sys;
  bool corrected = false;  ///< fluid.gradient = corrected
};

}  // namespace

std::unique_ptr<PressureScheme> make_standard_scheme(FluidCore& core, const FluidParameters& parameters) {
  return std::make_unique<StandardScheme>(core, parameters);
}

}  // namespace mpsfsi::fluid_detail
