// The explicit and implicit coupling schemes (coupling_scheme.hpp).
#include "coupling/coupling_scheme.hpp"

#include "core/binary_io.hpp"
#include "core/distribution.hpp"
#include "core/particles.hpp"
#include "core/stopwatch.hpp"
#include "coupling/fsi_interface.hpp"
#include "solid/solid_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace mpsfsi {

void CouplingScheme::save_state(BinaryWriter& out) const {
  out.section("coupling_scheme");
  out.string(name());
}

void CouplingScheme::load_state(BinaryReader& in) {
  in.expect_section("coupling_scheme");
  const std::string got = in.string("the coupling scheme");
  if (got != name()) in.fail("the checkpoint's coupling scheme is " + got + ", this run's " + name());
}

std::array<Participant*, 2> CouplingParticipants::participants() const { return {&fluid, &solid}; }

namespace {

/// One coupled step: (a) the fluid's view of the solid (the mid-step prediction, or x + d with velocity d / dt
/// for a given displacement d), given to the fluid as typed data, the fluid step, (b) the load, (c) the solid.
void coupled_step(const CouplingParticipants& c, const Real t, const Real dt, const int n_sub,
                  const DataVector* displacement, CouplingWindow& w) {
  auto t0 = Clock::now();
  c.fluid.set_solid_boundary(displacement ? c.interface.prepare_fluid_boundary(dt, *displacement)
                                           : c.interface.prepare_fluid_boundary(dt));
  w.t_coupling += seconds_since(t0);
  t0 = Clock::now();
  w.fluid = c.fluid.advance(t, dt);
  w.t_fluid += seconds_since(t0);
  t0 = Clock::now();
  c.interface.compute_load();
  w.t_coupling += seconds_since(t0);
  t0 = Clock::now();
  c.interface.advance_solid(c.solid, t, dt, n_sub);
  w.t_solid += seconds_since(t0);
}

class ExplicitScheme : public CouplingScheme {
 public:
  explicit ExplicitScheme(const CouplingParticipants& c) : c_(c) {}
  CouplingWindow advance(const Real t, const Real dt, const int n_sub) override {
    CouplingWindow w;
    coupled_step(c_, t, dt, n_sub, nullptr, w);
    return w;
  }
  std::string name() const override { return "explicit"; }

 private:
  CouplingParticipants c_;
};

class ImplicitScheme : public CouplingScheme {
 public:
  ImplicitScheme(const ImplicitCouplingParameters& parameters, const CouplingParticipants& c,
                 std::unique_ptr<Acceleration> acceleration)
      : parameters_(parameters), c_(c), acceleration_(std::move(acceleration)) {
    if (!acceleration_) acceleration_ = make_acceleration(parameters.acceleration, dim, c.distribution.comm());
  }

  CouplingWindow advance(const Real t, const Real dt, const int n_sub) override {
    CouplingWindow w;
    auto t0 = Clock::now();
    save();
    const std::vector<GlobalId> ids = c_.interface.solid_ids();
    // An RMS displacement of 1e-6 dp per solid particle over the step counts as none (a solid at rest).
    unsigned long long n_ids = ids.size();
    MPI_Allreduce(MPI_IN_PLACE, &n_ids, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, c_.distribution.comm());
    const Real floor = 1e-6 * c_.dp * std::sqrt(static_cast<Real>(n_ids));
    DataVector d = c_.interface.predicted_displacement(dt);
    w.t_coupling += seconds_since(t0);
    for (int k = 0;; ++k) {
      t0 = Clock::now();
      if (k > 0) restore();
      c_.fluid.set_density_tolerance_cap(fluid_density_tolerance(d, floor, n_ids));
      w.t_coupling += seconds_since(t0);
      coupled_step(c_, t, dt, n_sub, &d, w);
      t0 = Clock::now();
      const DataVector hd = c_.interface.step_displacement(ids);
      w.iterations = k + 1;
      w.residual = relative_residual(d, hd, floor, c_.distribution.comm());
      if (w.residual <= parameters_.tolerance || k + 1 >= parameters_.max_iterations) {
        w.converged = w.residual <= parameters_.tolerance;
        w.t_coupling += seconds_since(t0);
        break;
      }
      d = acceleration_->next(ids, d, hd);
      w.t_coupling += seconds_since(t0);
    }
    acceleration_->end_window();
    return w;
  }
  std::string name() const override { return "implicit"; }
  void save_state(BinaryWriter& out) const override {
    CouplingScheme::save_state(out);
    acceleration_->save_state(out);
  }
  void load_state(BinaryReader& in) override {
    CouplingScheme::load_state(in);
    acceleration_->load_state(in, c_.interface.solid_ids());
  }

 private:
  /// The density error the fluid's pressure solve may leave in an iteration on the displacement d: a share
  /// kFluidShare of the coupling's tolerance, in the units of the density error. A residual r of the pressure
  /// equation moves the particles by about (r dt^2 / rho) dp (a density error of e n0 is a compression of e dp),
  /// so the solve stops at kFluidShare tolerance rms(d) / dp, rms(d) the RMS of d per solid particle (not
  /// below the floor that counts as a solid at rest). A solve stopped at the coupling's own tolerance would make
  /// H(d) noisy at the level the iteration must resolve, and light structures (added mass much larger than the
  /// solid's) amplify that noise beyond it.
  Real fluid_density_tolerance(const DataVector& d, const Real floor, const unsigned long long n_ids) const {
    static constexpr Real kFluidShare = 0.1;
    const Real norm = std::max(std::sqrt(global_dot(d, d, c_.distribution.comm())), floor);
    const Real rms = norm / std::sqrt(std::max<Real>(1, static_cast<Real>(n_ids)));
    return kFluidShare * parameters_.tolerance * rms / c_.dp;
  }

  /// The state at the start of the window: this rank's particles (owned and ghosts, every array) with the ghost
  /// plan, the participants' iteration checkpoints and the interface's totals.
  void save() {
    saved_particles_ = c_.particles;
    saved_plan_ = c_.distribution.save_plan();
    BinaryWriter interface;
    c_.interface.save_state(interface);
    saved_interface_ = std::move(interface.bytes());
    for (Participant* q : c_.participants()) q->store_iteration_checkpoint();
  }
  /// Back to the start of the window, bit for bit: the same particles in the same order on every rank.
  void restore() {
    c_.particles.assign_from(saved_particles_);
    c_.distribution.restore_plan(saved_plan_);
    BinaryReader interface(saved_interface_, "the coupled step's start");
    c_.interface.load_state(interface);
    for (Participant* q : c_.participants()) q->reload_iteration_checkpoint();
  }

  ImplicitCouplingParameters parameters_;
  CouplingParticipants c_;
  std::unique_ptr<Acceleration> acceleration_;
  ParticleSet saved_particles_;
  std::shared_ptr<const Distribution::Plan> saved_plan_;
  std::string saved_interface_;
};

}  // namespace

std::unique_ptr<CouplingScheme> make_coupling_scheme(const CouplingParameters& parameters,
                                                     const CouplingParticipants& participants,
                                                     std::unique_ptr<Acceleration> acceleration) {
  switch (parameters.scheme) {
    case CouplingSchemeKind::explicit_scheme:
      return std::make_unique<ExplicitScheme>(participants);
    case CouplingSchemeKind::implicit_scheme:
      if (parameters.implicit.max_iterations < 1 || !(parameters.implicit.tolerance > 0))
        throw std::invalid_argument("coupling.implicit: max_iterations >= 1 and tolerance > 0 expected");
      return std::make_unique<ImplicitScheme>(parameters.implicit, participants, std::move(acceleration));
  }
  throw std::invalid_argument("coupling.scheme: unknown scheme");
}

}  // namespace mpsfsi
