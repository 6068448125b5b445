// The run loop: fluid step, solid sub-steps, state checks (non-finite or runaway velocity, solid leaving
// the domain), frames, probes and receivers, progress line and JSON-lines run log, checkpoints and restarts
// (the run loop's own state plus each participant's save_state / load_state, in named sections). With both
// fluid and solid the steps go through the FsiInterface participant loop (coupling/fsi_interface.hpp), with
// the solid's bond damping and the load relaxation of the case's coupling map. On several ranks the
// particles are distributed (core/distribution.hpp): each rank steps, checks and writes (one piece per
// frame) its owned particles, and checkpoints gather the state by global id on rank 0; fluid, solid and
// coupling each renew owners and ghosts when they need them.
#include "coupling/simulation.hpp"

#include "core/distribution.hpp"
#include "core/files.hpp"
#include "core/interrupt.hpp"
#include "core/output_lock.hpp"
#include "core/stopwatch.hpp"
#include "core/text.hpp"
#include "coupling/checkpoint.hpp"
#include "coupling/coupling_scheme.hpp"
#include "coupling/fsi_interface.hpp"
#include "coupling/time_step_policy.hpp"
#include "coupling/rank0.hpp"
#include "coupling/run_log.hpp"

#include "fluid/fluid_solver.hpp"
#include "io/probes.hpp"
#include "io/receivers.hpp"
#include "io/vtk_writer.hpp"
#include "solid/solid_solver.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>

namespace mpsfsi {

namespace {

int rank_of(MPI_Comm comm) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  return rank;
}

int size_of(MPI_Comm comm) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  return size;
}

long peak_memory_kib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

/// Wall time above which a run's projection is called absurd (a week).
constexpr double absurd_wall_seconds = 7 * 24 * 3600.0;

std::string format_duration(const double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const auto t = static_cast<long>(s + 0.5);
  if (t >= 3600) return fmt::format("{}h{:02d}m", t / 3600, static_cast<int>((t % 3600) / 60));
  if (t >= 60) return fmt::format("{}m{:02d}s", t / 60, static_cast<int>(t % 60));
  return fmt::format("{}s", t);
}

/// Speed above which a particle counts as runaway: the fluid's sound speed c (the weakly compressible
/// model is meaningless beyond Mach 1) and the solid's P-wave speed (particle speed = wave speed means
/// strains of order one).
struct SpeedLimits {
  Real fluid = 0;
  std::vector<Real> solid;  ///< per solid material

  explicit SpeedLimits(const CaseSpec& spec) {
    for (const auto& m : spec.fluid_materials) fluid = std::max(fluid, m.c);
    for (const auto& m : spec.solid_materials) solid.push_back(p_wave_speed(m, spec.solid));
  }
};

/// Everything a run needs between steps.
class RunLoop {
 public:
  RunLoop(const CaseSpec& spec, Scene& scene, const RunSettings& settings, MPI_Comm comm)
      : spec_(spec), p_(scene.particles), settings_(settings), limits_(spec), comm_(comm),
        step_policy_({spec.time.end, spec.solid.dt, spec.coupling.subcycles}, comm),
        writer_(settings.output_dir, "particles", rank_of(comm), size_of(comm)),
        probes_(spec, scene.particles, rank_of(comm) == 0 ? settings.output_dir + "/probes.csv" : std::string(),
                appends("probes.csv")),
        receivers_(spec, scene.particles, rank_of(comm) == 0 ? settings.output_dir + "/receivers.csv" : std::string(),
                   appends("receivers.csv")),
        log_(settings.output_dir, appends("run.jsonl"), settings.quiet, rank_of(comm)) {
    MPI_Comm_rank(comm, &rank_);
    MPI_Comm_size(comm, &n_ranks_);
    // The scene is whole on every rank here: count, then distribute.
    initial_fluid_ = fluid_per_body(false);
    const bool has_fluid = p_.n_of_kind(ParticleKind::fluid) > 0, has_solid = p_.n_of_kind(ParticleKind::solid) > 0;
    has_solid_ = has_solid;
    DistributionSettings ds;
    // The halo: the fluid's neighbour radius plus the skin (the owners and ghosts are renewed when a particle
    // has moved half of it).
    ds.method = spec.parallel.partition;
    ds.imbalance_threshold = spec.parallel.imbalance;
    ds.skin = spec.parallel.skin * spec.dp;
    ds.halo_width = std::max(has_fluid ? fluid_interaction_radius(fluid_setup(spec)) : 0.0,
                             has_solid ? solid_interaction_radius(solid_setup(spec)) : 0.0) + ds.skin;
    dist_ = std::make_unique<Distribution>(comm, ds);
    dist_->distribute_replicated(p_, work_weights(p_.size()));
    if (has_fluid)
      fluid_ = std::make_unique<FluidSolver>(fluid_setup(spec), p_, *dist_, has_solid ? FsiInterface::fluid_options() : FluidOptions{});
    // The solid and the coupling, distributed like the fluid (their constructors are collectives that throw on
    // every rank alike).
    if (has_solid) {
      try {
        solid_ = std::make_unique<SolidSolver>(solid_setup(spec), p_, *dist_);
      } catch (const SetupError& e) {  // the case does not fit the scene: bad input (exit 2)
        throw CaseError(e.what());
      }
      solid_->set_output_directory(settings.output_dir, appends("fragments.csv"));
    }
    if (fluid_ && solid_) {
      FsiOptions fo;
      fo.load_relaxation = spec.coupling.load_relaxation;
      solid_->set_damping(spec.coupling.solid_damping);
      coupling_ = std::make_unique<FsiInterface>(spec, p_, fo, dist_.get());
      coupling_->initialize();
      scheme_ = make_coupling_scheme(spec.coupling, CouplingParticipants{spec.dp, p_, *dist_, *fluid_, *solid_, *coupling_});
      on_rank0(comm, [&] { coupling_->open_csv(settings.output_dir + "/interface.csv", appends("interface.csv")); });
    }
    check_output_fields();
    writer_.set_fields(spec.output.fields);
    summary_.pvd_path = writer_.pvd_path();
    next_output_ = spec.output.interval;
    next_probe_ = spec.output.probe_interval.value_or(0);
    if (settings.restart) load_checkpoint(*settings.restart);
  }

  RunSummary run() {
    const auto t_start = Clock::now();
    t_begin_ = t_;
    step_begin_ = step_;
    if (!settings_.restart) {
      write_output();
      if (spec_.output.probe_interval) record_probes();
      receivers_.record_if_due(t_, p_, comm_);
    }
    report_projection();
    const Real eps = 1e-12 * std::max<Real>(1, spec_.time.end);
    const Real every = settings_.checkpoint_every;
    const auto next_checkpoint_after = [&](const Real t) { return (std::floor((t + eps) / every) + 1) * every; };
    Real next_checkpoint = every > 0 ? next_checkpoint_after(t_) : 0;
    Real last_checkpoint = settings_.restart ? t_ : -1;
    const auto more_steps = [&] { return settings_.max_steps == 0 || step_ - step_begin_ < settings_.max_steps; };
    Real last_frame = t_;
    while (t_ < spec_.time.end - eps && more_steps() && !interrupted()) {
      keep_last_good();
      step();
      receivers_.record_if_due(t_, p_, comm_);
      if (spec_.output.probe_interval && t_ >= next_probe_ - eps) {
        record_probes();
        next_probe_ = next_after(next_probe_, *spec_.output.probe_interval, eps);
      }
      report_progress(t_start, false);
      if (step_ - step_begin_ == 20) report_measured_projection(t_start);
      if (t_ >= next_output_ - eps) {
        write_output();
        last_frame = t_;
        // The next output time after t_: one addition as a rule (bit for bit the accumulated times), several
        // intervals at once when a step spans more than one.
        next_output_ = next_after(next_output_, spec_.output.interval, eps);
      }
      if (every > 0 && t_ >= next_checkpoint - eps) {
        write_checkpoint_now();
        last_checkpoint = t_;
        next_checkpoint = next_checkpoint_after(t_);
      }
    }
    // The state reached is always the last frame: at an end time between two output times, after --max-steps
    // or a signal.
    if (last_frame != t_) write_output();
    // The end state, to extend the run; after a signal always, to continue it.
    if ((every > 0 || summary_.interrupted_by != 0) && last_checkpoint != t_) write_checkpoint_now();
    report_progress(t_start, true);
    if (summary_.interrupted_by != 0)
      log_.event(fmt::format("{{\"event\":\"interrupted\",\"signal\":\"{}\",\"step\":{},\"t\":{:.9g}}}",
                             signal_name(summary_.interrupted_by), step_, t_));
    summary_.n_steps = step_;
    summary_.end_time = t_;
    summary_.wall_seconds = seconds_since(t_start);
    summary_.peak_memory_kib = peak_memory_kib();
    if (n_ranks_ > 1) MPI_Allreduce(MPI_IN_PLACE, &summary_.peak_memory_kib, 1, MPI_LONG, MPI_MAX, comm_);
    summary_.n_ranks = n_ranks_;
    if (n_ranks_ > 1) {
      unsigned long long owned[2] = {p_.n_owned(), ~static_cast<unsigned long long>(p_.n_owned())};
      MPI_Allreduce(MPI_IN_PLACE, owned, 2, MPI_UNSIGNED_LONG_LONG, MPI_MAX, comm_);
      summary_.owned_max = owned[0];
      summary_.owned_min = ~owned[1];
      const DistributionStats& d = dist_->stats();
      double t = d.t_partition + d.t_migrate + d.t_halo;
      MPI_Allreduce(MPI_IN_PLACE, &t, 1, MPI_DOUBLE, MPI_MAX, comm_);
      summary_.t_halo = t;
      summary_.n_partitions = d.n_partitions;
    }
    if (rank_ == 0) {
      std::string by_limit;
      for (const auto& [name, n] : summary_.steps_by_limit)
        by_limit += fmt::format("{}\"{}\":{}", by_limit.empty() ? "" : ",", name, n);
      log_.event(fmt::format(
          "{{\"event\":\"summary\",\"steps\":{},\"t\":{:.9g},\"wall\":{:.3f},\"fluid\":{:.3f},\"solid\":{:.3f},"
          "\"coupling\":{:.3f},\"output\":{:.3f},\"removed\":{},\"put_back\":{},\"subcycles_raised_steps\":{},"
          "\"peak_memory_kib\":{},\"dt_min\":{:.6g},\"t_of_dt_min\":{:.9g},\"limit_of_dt_min\":\"{}\","
          "\"steps_by_limit\":{{{}}}{}}}",
          step_, t_, summary_.wall_seconds, summary_.t_fluid, summary_.t_solid, summary_.t_coupling, summary_.t_output,
          summary_.n_removed, summary_.n_put_back, summary_.n_subcycles_raised, summary_.peak_memory_kib, summary_.dt_min,
          summary_.t_of_dt_min, summary_.limit_of_dt_min, by_limit,
          summary_.coupling_windows > 0
              ? fmt::format(",\"coupling_iterations\":{},\"coupling_iterations_max\":{},\"coupling_windows\":{},"
                            "\"coupling_unconverged\":{}",
                            summary_.coupling_iterations, summary_.coupling_iterations_max, summary_.coupling_windows,
                            summary_.n_unconverged)
              : std::string()));
    }
    return summary_;
  }

 private:
  /// Whether a signal asked the run to stop (core/interrupt.hpp): every rank's flag, so that all stop after the
  /// same step (a collective). Sets summary_.interrupted_by.
  bool interrupted() {
    int signo = interrupt_signal();
    if (n_ranks_ > 1) MPI_Allreduce(MPI_IN_PLACE, &signo, 1, MPI_INT, MPI_MAX, comm_);
    summary_.interrupted_by = signo;
    return signo != 0;
  }

  /// Rank 0: throws OutputError when the output folder was removed or replaced (core/output_lock.hpp).
  void check_output_folder() const {
    if (settings_.output_lock == nullptr) return;
    const std::string lost = settings_.output_lock->lost();
    if (!lost.empty()) throw OutputError(lost);  // stopped_by_output adds that its files are gone
  }

  void step() {
    const StepPlan plan = step_policy_.plan(t_, fluid_.get(), solid_.get());
    Real dt = plan.dt;
    const int n_sub = plan.n_sub;
    const std::string& limit = plan.limit;
    step_limit_ = limit;
    if (plan.subcycles_raised) {
      ++summary_.n_subcycles_raised;
      if (!raised_said_)
        log_.note(fmt::format("step {}: subcycles {} would give a solid dt of {:.3e} s > the solid's stable dt {:.3e} s "
                              "(solid.dt_factor dp / c_p); raised to {} (and whenever needed from now on, counted in "
                              "the summary)",
                              step_ + 1, spec_.coupling.subcycles, dt / spec_.coupling.subcycles, plan.solid_stable_dt,
                              n_sub));
      raised_said_ = true;
    }
    ++summary_.steps_by_limit[limit];
    if (limit != "end time" && (summary_.dt_min == 0 || dt < summary_.dt_min)) {
      summary_.dt_min = dt;
      summary_.t_of_dt_min = t_;
      summary_.limit_of_dt_min = limit;
    }
    if (n_ranks_ > 1 && step_ % repartition_every == 0) {
      const auto t0 = Clock::now();
      const std::vector<Real> w = work_weights(p_.n_owned());
      if (dist_->imbalance(p_, w) > dist_->settings().imbalance_threshold) dist_->partition(p_, w);
      summary_.t_fluid += seconds_since(t0);
    }
    std::string window_finding;  // the implicit coupling's verdict, the same on every rank
    try {
      if (scheme_) {  // fluid, load, solid: coupling/coupling_scheme.hpp
        const CouplingWindow w = scheme_->advance(t_, dt, n_sub);
        last_fluid_ = w.fluid;
        summary_.t_fluid += w.t_fluid;
        summary_.t_solid += w.t_solid;
        summary_.t_coupling += w.t_coupling;
        window_finding = note_window(w);
      } else if (fluid_) {
        const auto t0 = Clock::now();
        last_fluid_ = fluid_->advance(t_, dt);
        summary_.t_fluid += seconds_since(t0);
      } else if (solid_) {
        const auto t0 = Clock::now();
        const Real dts = dt / n_sub;
        for (int k = 0; k < n_sub; ++k) solid_->advance(t_ + k * dts, dts);
        summary_.t_solid += seconds_since(t0);
      }
      if (fluid_) {
        summary_.n_removed += last_fluid_.n_removed;
        summary_.n_put_back += last_fluid_.n_put_back;
        if (last_fluid_.n_removed > 0)
          log_.note(fmt::format("step {}: {} fluid particle(s) left the domain and were removed ({} so far)", step_ + 1,
                                last_fluid_.n_removed, summary_.n_removed));
      }
    } catch (const RunFailure& e) {
      fail_within_step(e.what());
    } catch (const std::exception& e) {
      fail_within_step(fmt::format("step {} (t = {:.6g} s): {}", step_ + 1, t_, e.what()));
    }
    // The state checks: each rank looks at its particles, the first finding stops every rank.
    std::string finding = window_finding;
    if (finding.empty()) {  // (the window's verdict is every rank's: all skip the checks alike)
      try {
        check_state(step_ + 1, t_ + dt);
        if (last_fluid_.n_removed > 0) check_losses(step_ + 1, t_ + dt);
      } catch (const RunFailure& e) {
        finding = e.what();
      }
    }
    finding = agreed_message(comm_, finding);
    if (!finding.empty()) fail(finding);
    t_ += dt;
    ++step_;
    dt_ = dt;
    limit_ = limit;
    summary_.last_subcycles = n_sub;
    summary_.last_solid_dt = dt / n_sub;
  }

  /// The implicit coupling's iterations of the window into the summary; a window that did not converge is
  /// said once and counted, or (coupling.implicit.on_max_iterations: stop) returned as the finding that stops
  /// the run (every rank has the same verdict: the residual is reduced over the ranks).
  std::string note_window(const CouplingWindow& w) {
    last_window_ = w;
    if (scheme_->name() != "implicit") return {};
    summary_.coupling_iterations += static_cast<std::size_t>(w.iterations);
    summary_.coupling_iterations_max = std::max(summary_.coupling_iterations_max, w.iterations);
    ++summary_.coupling_windows;
    if (w.converged) return {};
    ++summary_.n_unconverged;
    const ImplicitCouplingParameters& ic = spec_.coupling.implicit;
    const std::string what = fmt::format(
        "step {} (t = {:.6g} s): the implicit coupling did not converge in coupling.implicit.max_iterations = {} "
        "(residual {:.3g}, tolerance {:.3g})",
        step_ + 1, t_, ic.max_iterations, w.residual, ic.tolerance);
    if (ic.on_max_iterations == NonConvergence::stop)
      return what + "; coupling.implicit.on_max_iterations = stop (raise max_iterations, loosen the tolerance, or "
                    "choose another acceleration)";
    if (!unconverged_said_)
      log_.note(what + "; the run goes on with the last iterate (said once; the summary counts such steps)");
    unconverged_said_ = true;
    return {};
  }

  /// Non-finite state, runaway speed, solid particles leaving the domain: the first offender is named.
  void check_state(const std::size_t step, const Real t) const {
    for (std::size_t i = 0; i < p_.n_owned(); ++i) {
      const auto where = [&] {
        return fmt::format("particle {} ({} of body '{}') at {}", p_.global_id[i], to_string(p_.kind[i]),
                           p_.bodies[p_.body[i]].name, show_point(p_.position[i]));
      };
      if (!p_.position[i].allFinite() || !p_.velocity[i].allFinite())
        throw RunFailure(fmt::format("step {} (t = {:.6g} s): {} has a non-finite position or velocity; the run went "
                                     "unstable (reduce dt or the CFL number)",
                                     step, t, where()));
      const Real speed = p_.velocity[i].norm();
      if (p_.kind[i] == ParticleKind::fluid && limits_.fluid > 0 && speed > limits_.fluid)
        throw RunFailure(fmt::format("step {} (t = {:.6g} s): {} moves at {:.4g} m/s, faster than the fluid's sound "
                                     "speed c = {:.4g} m/s: runaway velocity (reduce dt or the CFL number, or raise c)",
                                     step, t, where(), speed, limits_.fluid));
      if (p_.kind[i] == ParticleKind::solid) {
        const auto m = static_cast<std::size_t>(p_.material[i]);
        if (m < limits_.solid.size() && speed > limits_.solid[m])
          // A clamped particle moves with the tank: its speed is the prescribed motion's, not the solver's.
          throw RunFailure(
              p_.clamped[i] != 0
                  ? fmt::format("step {} (t = {:.6g} s): {} is clamped and moves at {:.4g} m/s with the prescribed "
                                "tank motion, faster than the P-wave speed {:.4g} m/s of its material: the tank_motion "
                                "is too violent for the solid to follow (expected a motion whose wall speed stays well "
                                "below that speed: a smaller amplitude or a longer period)",
                                step, t, where(), speed, limits_.solid[m])
                  : fmt::format("step {} (t = {:.6g} s): {} moves at {:.4g} m/s, faster than the P-wave speed "
                                "{:.4g} m/s of its material: runaway velocity (reduce the solid dt)",
                                step, t, where(), speed, limits_.solid[m]));
        if (!spec_.domain.contains(p_.position[i]))
          throw RunFailure(fmt::format("step {} (t = {:.6g} s): {} left the domain {}", step, t, where(),
                                       show_box(spec_.domain)));
      }
    }
  }

  /// output.fields names fields of this case: the solvers registered theirs above (a case without a solid has
  /// no von_mises, for example), so the names are checked here rather than when the case is read.
  void check_output_fields() const {
    std::vector<std::string> known;
    for (const auto& kv : p_.scalar_fields()) known.push_back(kv.first);
    for (const auto& kv : p_.vector_fields()) known.push_back(kv.first);
    for (const auto& name : spec_.output.fields)
      if (!p_.has_scalar_field(name) && !p_.has_vector_field(name))
        throw CaseError(fmt::format("{}: output.fields: '{}' is not a field of this case; expected some of: {} (the "
                                    "arrays velocity, kind, body, material, clamped and global_id are always written)",
                                    spec_.file, name.size() > 64 ? name.substr(0, 64) + "..." : name,
                                    fmt::join(known, ", ")));
  }

  /// Fluid particles of each body (by body index), over the ranks (sum) or on this rank.
  std::vector<std::size_t> fluid_per_body(const bool over_ranks = true) const {
    std::vector<unsigned long long> n(p_.bodies.size(), 0);
    for (std::size_t i = 0; i < p_.n_owned(); ++i)
      if (p_.kind[i] == ParticleKind::fluid) ++n[p_.body[i]];
    if (over_ranks && n_ranks_ > 1)
      MPI_Allreduce(MPI_IN_PLACE, n.data(), static_cast<int>(n.size()), MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm_);
    return {n.begin(), n.end()};
  }

  /// A fluid body that lost more than fluid.max_loss of its particles through the domain's boundary stops
  /// the run: the fluid fell or was flung out, and what is left is not the case that was asked for.
  void check_losses(const std::size_t step, const Real t) const {
    const std::vector<std::size_t> now = fluid_per_body();
    for (std::size_t b = 0; b < now.size(); ++b) {
      if (initial_fluid_[b] == 0) continue;
      const std::size_t lost = initial_fluid_[b] - std::min(now[b], initial_fluid_[b]);
      const Real share = static_cast<Real>(lost) / static_cast<Real>(initial_fluid_[b]);
      if (share > spec_.fluid.max_loss)
        throw RunFailure(fmt::format(
            "step {} (t = {:.6g} s): {} of the {} particles ({:.1f} %) of fluid body '{}' have left the domain "
            "{}, more than fluid.max_loss = {:g} %; the fluid fell or was flung out "
            "(dt {:.3g} s limited by {}: check time.dt_max, time.cfl and the gravity, and that the walls hold the "
            "fluid)",
            step, t, lost, initial_fluid_[b], 100 * share, p_.bodies[b].name, show_box(spec_.domain),
            100 * spec_.fluid.max_loss, last_fluid_.dt, step_limit_));
    }
  }

  /// Before the first step: the number of steps the run needs at its first dt (and the solid's sub-steps),
  /// with a warning when that cannot finish in any sensible time.
  void report_projection() {
    const RunProjection r = project_run(spec_, p_, t_, comm_);  // counts summed over the ranks (a collective)
    log_.print(r.text());
  }

  /// After the first steps: the projected number of steps and wall time at the measured rate.
  void report_measured_projection(const Clock::time_point t_start) {
    if (rank_ != 0 || !(dt_ > 0)) return;
    const double wall = seconds_since(t_start);
    const double steps = static_cast<double>(step_ - step_begin_);
    const double remaining_steps = (spec_.time.end - t_) / dt_;
    const double remaining_wall = wall / steps * remaining_steps;
    log_.event(fmt::format("{{\"event\":\"projection\",\"step\":{},\"remaining_steps\":{:.4g},\"remaining_wall\":{:.4g}}}",
                           step_, remaining_steps, remaining_wall));
    log_.note(fmt::format("projection after {} steps: about {:.3g} more steps at dt {:.3g} s ({}), {} of wall time at "
                          "{:.3g} steps/s",
                          step_ - step_begin_, remaining_steps, dt_, limit_, format_duration(remaining_wall),
                          steps / std::max(wall, 1e-9)));
    if (remaining_wall > absurd_wall_seconds)
      log_.print(fmt::format("warning: at this rate the run needs {} of wall time; it cannot finish in any sensible "
                             "time (coarsen dp, shorten time.end, or look at the dt limit '{}')",
                             format_duration(remaining_wall), limit_));
  }

  /// Keep a copy of the particle set as the frame written if a later step fails. The copy costs about as much
  /// as a cheap solid step (docs/performance.md, ## Lamb's problem), so it is taken every k steps, with k from the
  /// measured copy and step times such that the copies take at most ~2 % of the run; the frame is then at
  /// most k steps older than the failing step (its time is in the message).
  void keep_last_good() {
    const auto now = Clock::now();
    if (have_last_good_) step_seconds_ = std::chrono::duration<double>(now - last_step_start_).count();
    last_step_start_ = now;
    if (have_last_good_ && ++steps_since_copy_ < copy_every_) return;
    last_good_ = p_;
    last_good_t_ = t_;
    last_good_step_ = step_;
    have_last_good_ = true;
    steps_since_copy_ = 0;
    const double copy_seconds = seconds_since(now);
    last_step_start_ = Clock::now();  // the step's time without the copy
    if (step_seconds_ > 0)
      copy_every_ = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(copy_seconds / (0.02 * step_seconds_))));
    if (n_ranks_ > 1) {  // every rank copies at the same steps: a failure writes one state of all pieces
      unsigned long long every = copy_every_;
      MPI_Allreduce(MPI_IN_PLACE, &every, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, comm_);
      copy_every_ = every;
    }
  }

  /// A step that threw on this rank: on one rank, fail(); on several, the other ranks may be waiting in a
  /// collective of the step, so this rank says why and ends the job (exit 3).
  [[noreturn]] void fail_within_step(const std::string& diagnosis) {
    if (n_ranks_ == 1) fail(diagnosis);
    std::fprintf(stderr, "mpsfsi: error (rank %d of %d): %s\n", rank_, n_ranks_, diagnosis.c_str());
    std::fflush(stderr);
    MPI_Abort(comm_, 3);
    std::abort();  // not reached
  }

  /// Write the last good state as a frame, log the diagnosis, and throw (all ranks together).
  [[noreturn]] void fail(const std::string& diagnosis) {
    std::string frame;
    try {
      // A series never repeats a time: when the last good state is the last frame's (a failure in the first
      // steps after a frame), that frame is it.
      if (writer_.n_frames() > 0 && writer_.frames().back().first == last_good_t_) {
        frame = (std::filesystem::path(settings_.output_dir) / writer_.frames().back().second).string() + " (already written)";
      } else {
        on_every_rank(comm_, [&] { writer_.write_piece(last_good_, last_good_t_); });
        on_rank0(comm_, [&] { frame = writer_.commit_frame(last_good_t_); });
        if (rank_ != 0) writer_.commit_frame(last_good_t_);
      }
    } catch (const std::exception& e) {
      frame = std::string("(could not be written: ") + e.what() + ")";
    }
    log_.event(fmt::format("{{\"event\":\"failure\",\"step\":{},\"t\":{:.9g},\"diagnosis\":\"{}\"}}", step_ + 1, t_,
                           RunLog::json_escape(diagnosis)));
    log_.end_line();
    throw RunFailure(fmt::format("{}\nlast good frame (t = {:.6g} s, after step {}): {}", diagnosis, last_good_t_,
                                 last_good_step_, frame));
  }

  /// The next output time after t_ of a schedule due at `due`: one addition as a rule (bit for bit the
  /// accumulated times), several intervals at once when a step spans more than one.
  Real next_after(Real due, const Real interval, const Real eps) const {
    const Real behind = std::floor((t_ + eps - due) / interval) + 1;
    due += behind > 1 ? behind * interval : interval;
    return due > t_ + eps ? due : t_ + interval;
  }

  /// A row of probes.csv at t_ (output.probe_interval; without it the rows come with the frames).
  void record_probes() {
    const std::vector<Real> values = probes_.evaluate(p_, t_, comm_);
    on_rank0(comm_, [&] { probes_.record(t_, values); });
  }

  /// A frame, the probes and the interface table at t_. A file that cannot be written (disk full) stops the
  /// run on every rank with OutputError; the series lists only the complete frames written before.
  void write_output() {
    const auto t0 = Clock::now();
    // The solid's derived fields and fragments.csv (written by rank 0 once every rank is past the collectives).
    if (solid_) on_every_rank(comm_, [&] { solid_->prepare_output(t_); });
    const std::vector<Real> probe_values =
        spec_.output.probe_interval ? std::vector<Real>{} : probes_.evaluate(p_, t_, comm_);
    try {
      // Every rank writes its piece; once all are complete, rank 0 adds the frame to the series.
      on_every_rank(comm_, [&] {
        if (!log_.error().empty()) throw OutputError(log_.error());  // found on rank 0 alone, stops all ranks here
        if (rank_ == 0) check_output_folder();
        writer_.write_piece(p_, t_);
      });
      on_rank0(comm_, [&] {
        writer_.commit_frame(t_);
        if (!spec_.output.probe_interval) probes_.record(t_, probe_values);
        if (coupling_) coupling_->write_csv(t_);
      });
      if (rank_ != 0) writer_.commit_frame(t_);
    } catch (const OutputError& e) {
      throw OutputError(stopped_by_output(e.what()));
    }
    summary_.t_output += seconds_since(t0);
  }

  /// The message of a run stopped because a file could not be written; also logged in run.jsonl.
  std::string stopped_by_output(const std::string& what) {
    // A folder removed while a file was written: the write's error ("No such file") names the symptom, the
    // lock the cause.
    const std::string lost = settings_.output_lock != nullptr ? settings_.output_lock->lost() : std::string();
    const bool gone = !lost.empty();
    const std::string cause = gone && what.find(lost) == std::string::npos ? lost + " (" + what + ")" : what;
    const std::string frames =
        gone                     ? std::string("its files are gone with the folder")
        : writer_.n_frames() > 0
            ? fmt::format("{} lists the {} complete frame(s) up to t = {:.6g} s", writer_.pvd_path(), writer_.n_frames(),
                          writer_.frames().back().first)
            : fmt::format("no frame was written");
    const std::string text = fmt::format("{}\nthe run stopped at t = {:.6g} s (step {}); {}", cause, t_, step_, frames);
    // May fail as well on a full disk: the message on stderr is the one that counts.
    log_.event(fmt::format("{{\"event\":\"failure\",\"step\":{},\"t\":{:.9g},\"diagnosis\":\"{}\"}}", step_, t_,
                           RunLog::json_escape(text)));
    return text;
  }

  void report_progress(const Clock::time_point t_start, const bool final) {
    const bool periodic = step_ % static_cast<std::size_t>(std::max(1, settings_.log_every)) == 0 || step_ == 1;
    if (n_ranks_ > 1 && (periodic || final) && step_ != logged_step_) {
      report_distribution();  // a collective: every rank keeps logged_step_
      if (rank_ != 0) logged_step_ = step_;
    }
    if (rank_ != 0) return;
    const double wall = seconds_since(t_start);
    const double rate = wall > 0 ? static_cast<double>(step_ - step_begin_) / wall : 0;
    const double frac = spec_.time.end > 0 ? t_ / spec_.time.end : 1;
    // ETA from this session's progress (a restarted run began at t_begin_).
    const double done = spec_.time.end > t_begin_ ? (t_ - t_begin_) / (spec_.time.end - t_begin_) : 1;
    const double eta = done > 0 ? wall * (1 - done) / done : -1;
    std::string ppe, sub;
    if (fluid_) ppe = fmt::format(", PPE {} it (res {:.1e})", last_fluid_.iterations, last_fluid_.residual);
    if (fluid_ && solid_)
      sub = fmt::format(", subcycles {} (solid dt {:.2e} s)", summary_.last_subcycles, summary_.last_solid_dt);
    const bool implicit = scheme_ && scheme_->name() == "implicit";
    if (implicit) sub += fmt::format(", coupling {} it (res {:.1e})", last_window_.iterations, last_window_.residual);
    const std::string line = fmt::format("t = {:.5f} s ({:5.1f} %), step {}, {:.1f} steps/s, ETA {}, dt {:.2e} s ({}){}{}",
                                         t_, 100 * frac, step_, rate, format_duration(eta), dt_, limit_, ppe, sub);
    // A step is logged once: the final line of a run that ends on a periodic step is not written again.
    const bool due = (periodic || final) && step_ != logged_step_;
    if (due) logged_step_ = step_;
    log_.progress(line,
                  fmt::format("{{\"event\":\"step\",\"step\":{},\"t\":{:.9g},\"dt\":{:.6g},\"limit\":\"{}\","
                              "\"ppe_iterations\":{},\"ppe_solves\":{},\"ppe_residual\":{:.3g},\"put_back\":{},\"subcycles\":{},{}"
                              "\"wall\":{:.3f}}}",
                              step_, t_, dt_, limit_, last_fluid_.iterations, last_fluid_.solves, last_fluid_.residual,
                              last_fluid_.n_put_back,
                              summary_.last_subcycles,
                              implicit ? fmt::format("\"coupling_iterations\":{},\"coupling_residual\":{:.3g},"
                                                     "\"coupling_converged\":{},",
                                                     last_window_.iterations, last_window_.residual, last_window_.converged)
                                       : std::string(),
                              wall),
                  due, final);
  }

  /// Several ranks: the owned particles per rank, their imbalance, the time in owners and ghosts, the
  /// partitions so far (run.jsonl, event "distribution"; a collective).
  void report_distribution() {
    const DistributionStats& d = dist_->stats();
    unsigned long long owned = p_.n_owned();
    std::vector<unsigned long long> all(static_cast<std::size_t>(n_ranks_));
    MPI_Gather(&owned, 1, MPI_UNSIGNED_LONG_LONG, all.data(), 1, MPI_UNSIGNED_LONG_LONG, 0, comm_);
    double times[3] = {d.t_partition, d.t_migrate, d.t_halo};
    MPI_Allreduce(MPI_IN_PLACE, times, 3, MPI_DOUBLE, MPI_MAX, comm_);
    if (rank_ != 0) return;
    double mean = 0, largest = 0;
    for (const auto n : all) {
      mean += static_cast<double>(n) / n_ranks_;
      largest = std::max(largest, static_cast<double>(n));
    }
    log_.event(fmt::format(
        "{{\"event\":\"distribution\",\"step\":{},\"owned\":[{}],\"imbalance\":{:.4f},\"partitions\":{},"
        "\"t_partition\":{:.3f},\"t_migrate\":{:.3f},\"t_halo\":{:.3f}}}",
        step_, fmt::join(all, ","), mean > 0 ? largest / mean - 1 : 0.0, d.n_partitions, times[0], times[1], times[2]));
  }

  bool appends(const std::string& file) const {
    return std::find(settings_.append_files.begin(), settings_.append_files.end(), file) != settings_.append_files.end();
  }

  /// The run loop's own state: everything that decides the coming steps and outputs.
  void save_run_state(BinaryWriter& w) const {
    w.section("run");
    w.f64(t_);
    w.u64(step_);
    w.f64(dt_);
    w.string(limit_);
    w.f64(next_output_);
    w.f64(next_probe_);
    w.u64(summary_.n_removed);
    w.u64(summary_.n_put_back);
    w.u64(summary_.n_subcycles_raised);
    w.i64(summary_.last_subcycles);
    w.f64(summary_.last_solid_dt);
    w.boolean(raised_said_);
    w.i64(last_fluid_.iterations);
    w.f64(last_fluid_.residual);
    w.boolean(fluid_ != nullptr);
    w.boolean(solid_ != nullptr);
    w.boolean(coupling_ != nullptr);
    receivers_.save_state(w);
  }

  /// Writes checkpoint_<t>.chk into the output folder (rank 0, from every rank's particles gathered there);
  /// a failure stops the run on every rank.
  void write_checkpoint_now() {
    try {
      const ParticleSet all = dist_->gather(p_, 0);  // rank 0: every particle, rank by rank
      BinaryWriter distribution, scheme;
      dist_->save_state(distribution, p_, 0);
      if (scheme_) scheme_->save_state(scheme);  // a collective
      on_rank0(comm_, [&] {
        check_output_folder();
        write_checkpoint_on_rank0(all, distribution, scheme);
      });
    } catch (const OutputError& e) {
      throw OutputError(stopped_by_output(e.what()));
    }
  }

  void write_checkpoint_on_rank0(const ParticleSet& all, const BinaryWriter& distribution, const BinaryWriter& scheme) {
    const auto t0 = Clock::now();
    BinaryWriter w;
    save_run_state(w);
    all.save_state(w);
    w.bytes() += distribution.bytes();
    if (fluid_) fluid_->save_state(w);
    if (solid_) solid_->save_state(w);
    if (coupling_) coupling_->save_state(w);
    w.bytes() += scheme.bytes();
    w.section("end");
    receivers_.flush();
    CheckpointInfo info;
    info.case_name = spec_.name;
    info.case_file = spec_.file;
    std::error_code ec;
    const auto dir = std::filesystem::absolute(std::filesystem::path(spec_.file).parent_path(), ec);
    info.case_dir = ec ? std::string(".") : dir.lexically_normal().string();
    info.resolved_yaml = spec_.resolved_yaml;
    info.time = t_;
    info.step = step_;
    info.n_particles = all.size();
    info.n_ranks = n_ranks_;
    info.next_frame = writer_.next_frame();
    info.frames = writer_.frames();
    info.outputs = mark_outputs(settings_.output_dir, {"probes.csv", "interface.csv", "fragments.csv", "receivers.csv", "run.jsonl"});
    const std::time_t now = std::time(nullptr);
    char date[64] = "";
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S %z", std::localtime(&now));
    info.written_at = date;
    const std::string path = (std::filesystem::path(settings_.output_dir) / checkpoint_file_name(t_)).string();
    write_checkpoint(path, info, w.bytes());
    log_.event(fmt::format("{{\"event\":\"checkpoint\",\"step\":{},\"t\":{:.9g},\"file\":\"{}\"}}", step_, t_,
                           RunLog::json_escape(path)));
    log_.note(fmt::format("checkpoint at t = {:.6g} s (step {}): {} ({:.1f} MiB)", t_, step_, path,
                          static_cast<double>(w.bytes().size()) / (1024.0 * 1024.0)));
    written_.push_back(path);
    while (settings_.checkpoint_keep > 0 && written_.size() > static_cast<std::size_t>(settings_.checkpoint_keep)) {
      if (written_.front() != path) std::filesystem::remove(written_.front(), ec);
      written_.pop_front();
    }
    summary_.t_output += seconds_since(t0);
  }

  /// Restart: the state of the checkpoint replaces the initial one (the solvers were built from the
  /// initial scene, which gave them their reference data).
  void load_checkpoint(const Checkpoint& c) {
    BinaryReader in = c.payload();
    try {
      in.expect_section("run");
      t_ = in.f64("the time");
      step_ = in.u64("the step");
      dt_ = in.f64("the time step");
      limit_ = in.string("the time-step limit");
      next_output_ = in.f64("the next output time");
      next_probe_ = in.f64("the next probe time");
      summary_.n_removed = in.u64("the removed count");
      summary_.n_put_back = in.u64("the put-back count");
      summary_.n_subcycles_raised = in.u64("the raised-subcycles count");
      summary_.last_subcycles = static_cast<int>(in.i64("the subcycles"));
      summary_.last_solid_dt = in.f64("the solid time step");
      raised_said_ = in.boolean("a log flag");
      last_fluid_.iterations = static_cast<int>(in.i64("the pressure-solve iterations"));
      last_fluid_.residual = in.f64("the pressure-solve residual");
      const bool fluid = in.boolean("the fluid flag"), solid = in.boolean("the solid flag"),
                 coupled = in.boolean("the coupling flag");
      if (fluid != (fluid_ != nullptr) || solid != has_solid_ || coupled != (has_solid_ && fluid_ != nullptr))
        in.fail("the checkpoint's run has other participants (fluid, solid, coupling) than this case");
      receivers_.load_state(in);
      p_.drop_ghosts();
      p_.load_state(in);  // every particle, on every rank
      dist_->load_state(in, p_);
      if (fluid_) exact_ = fluid_->load_state(in);
      if (solid_) solid_->load_state(in);
      if (coupling_) coupling_->load_state(in);
      if (scheme_) scheme_->load_state(in);
      in.expect_section("end");
      if (!in.at_end()) in.fail("unexpected data after the state");
    } catch (const StateFormatError& e) {
      throw CaseError(std::string("checkpoint ") + e.what());
    }
    if (!exact_)
      log_.print("note: the pressure preconditioner the checkpoint's run kept between setups "
                 "(fluid.preconditioner_rebuild_every > 1) cannot be rebuilt here (it was saved on several ranks, or "
                 "the setting changed) and is set up anew: the continuation agrees with the original run to the "
                 "solver tolerance, not bit for bit");
    if (c.info.n_ranks != n_ranks_)
      log_.print(fmt::format("note: the checkpoint was written on {} rank(s), this run has {}: the particles are "
                             "partitioned anew and the continuation agrees with the original run to the solver "
                             "tolerance, not bit for bit",
                             c.info.n_ranks, n_ranks_));
    on_rank0(comm_, [&] {
      if (settings_.continue_series)
        writer_.adopt_existing(t_, c.info.next_frame);
      else
        writer_.set_next_frame(c.info.next_frame);
      log_.event(fmt::format("{{\"event\":\"restart\",\"step\":{},\"t\":{:.9g},\"checkpoint\":\"{}\"}}", step_, t_,
                             RunLog::json_escape(c.path)));
    });
    if (n_ranks_ > 1) {  // every piece continues with rank 0's frame number
      unsigned long long next = writer_.next_frame();
      MPI_Bcast(&next, 1, MPI_UNSIGNED_LONG_LONG, 0, comm_);
      writer_.set_next_frame(next);
    }
  }

  const CaseSpec& spec_;
  ParticleSet& p_;
  const RunSettings& settings_;
  const SpeedLimits limits_;
  MPI_Comm comm_;
  std::vector<std::size_t> initial_fluid_;  ///< fluid particles per body at the start of the case
  TimeStepPolicy step_policy_;
  std::string step_limit_ = "-";            ///< the dt limit of the step being taken
  std::size_t logged_step_ = static_cast<std::size_t>(-1);  ///< the last step written to run.jsonl
  VtkSeriesWriter writer_;
  ProbeWriter probes_;
  ReceiverWriter receivers_;  ///< receivers.csv (rank 0), rows every step or every receivers.interval
  RunLog log_;                ///< the progress line, notes and run.jsonl (the writers above make the folder)
  std::unique_ptr<Distribution> dist_;
  bool has_solid_ = false;  ///< the case has a solid
  /// Steps between checks of the owned work's balance (re-partition above the threshold).
  static constexpr std::size_t repartition_every = 20;
  /// The partition weights of the first n particles: their work in a fluid step (fluid_work_weight; solid
  /// particles 1).
  std::vector<Real> work_weights(const std::size_t n) const {
    std::vector<Real> w(n);
    for (std::size_t i = 0; i < n; ++i) w[i] = fluid_work_weight(p_.kind[i]);
    return w;
  }
  std::unique_ptr<FluidSolver> fluid_;
  std::unique_ptr<SolidSolver> solid_;
  std::unique_ptr<FsiInterface> coupling_;
  std::unique_ptr<CouplingScheme> scheme_;
  CouplingWindow last_window_;         ///< the last coupled window (iterations, residual)
  bool unconverged_said_ = false;
  bool raised_said_ = false;
  int rank_ = 0;
  ParticleSet last_good_;
  Real last_good_t_ = 0;               ///< time of last_good_
  std::size_t last_good_step_ = 0;     ///< steps done when last_good_ was taken
  bool have_last_good_ = false;
  std::size_t copy_every_ = 1, steps_since_copy_ = 0;
  double step_seconds_ = 0;            ///< wall time of the last step (without the copy)
  Clock::time_point last_step_start_;
  FluidStepReport last_fluid_;
  RunSummary summary_;
  Real t_ = 0, dt_ = 0;
  Real next_output_ = 0;               ///< time of the next frame (accumulated: saved, not recomputed)
  Real next_probe_ = 0;                ///< time of the next row of probes.csv with output.probe_interval (likewise)
  std::string limit_ = "-";
  std::size_t step_ = 0;
  int n_ranks_ = 1;
  Real t_begin_ = 0;                   ///< time and step at the start of this session (restart)
  std::size_t step_begin_ = 0;
  std::deque<std::string> written_;    ///< checkpoints this run wrote, oldest first
  bool exact_ = true;                  ///< restart: the coming steps are bit for bit the original run's
};

}  // namespace

RunProjection project_run(const CaseSpec& spec, const ParticleSet& p, const Real t, MPI_Comm comm) {
  RunProjection r;
  Real v_max = 0, nu = 0, c_p = 0;
  unsigned long long n_fluid = 0, n_solid = 0, n_all = p.n_owned();
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    const auto m = static_cast<std::size_t>(std::max<int>(0, p.material[i]));
    if (p.kind[i] == ParticleKind::fluid && m < spec.fluid_materials.size()) {
      ++n_fluid;
      v_max = std::max(v_max, p.velocity[i].norm());
      nu = std::max(nu, spec.fluid_materials[m].nu);
    } else if (p.kind[i] == ParticleKind::solid && m < spec.solid_materials.size()) {
      ++n_solid;
      c_p = std::max(c_p, p_wave_speed(spec.solid_materials[m], spec.solid));
    }
  }
  if (size_of(comm) > 1) {
    Real maxima[3] = {v_max, nu, c_p};
    unsigned long long counts[3] = {n_fluid, n_solid, n_all};
    MPI_Allreduce(MPI_IN_PLACE, maxima, 3, MPI_DOUBLE, MPI_MAX, comm);
    MPI_Allreduce(MPI_IN_PLACE, counts, 3, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm);
    v_max = maxima[0], nu = maxima[1], c_p = maxima[2];
    n_fluid = counts[0], n_solid = counts[1], n_all = counts[2];
  }
  const Real dt_solid = c_p > 0 ? spec.solid.dt_factor * spec.dp / c_p : 0;
  if (n_fluid > 0) {
    r.dt = fluid_stable_dt(spec.time, spec.dp, nu, spec.gravity.norm(), v_max, FluidOptions{}.viscous_number, &r.limit);
    if (n_solid > 0) r.subcycles = choose_subcycles(spec.coupling.subcycles, r.dt, dt_solid).n;
  } else if (n_solid > 0) {
    r.dt = spec.solid.dt ? *spec.solid.dt : dt_solid;
    r.limit = spec.solid.dt ? "fixed" : "solid stability";
  }
  if (!(r.dt > 0)) return r;
  r.n_steps = std::max<Real>(0, spec.time.end - t) / r.dt;
  r.n_solid_steps = n_solid == 0 ? 0 : n_fluid > 0 ? r.n_steps * r.subcycles : r.n_steps;
  r.particle_steps = static_cast<double>(n_all) * (n_fluid > 0 ? r.n_steps : 0) +
                     static_cast<double>(n_solid) * r.n_solid_steps;
  r.absurd = !(r.particle_steps <= 1e12) || !(r.n_steps <= 1e8);
  return r;
}

std::string RunProjection::text() const {
  if (!(dt > 0)) return "projection: nothing to step";
  std::string s = fmt::format("projection: {:.3g} steps of dt = {:.3g} s ({})", n_steps, dt, limit);
  if (subcycles > 1) s += fmt::format(", each with {} solid sub-steps ({:.3g} in all)", subcycles, n_solid_steps);
  s += fmt::format("; {:.3g} particle-steps", particle_steps);
  if (absurd)
    s += fmt::format("\nwarning: {:.3g} particle-steps cannot finish in any sensible time (weeks or more on one "
                     "core); check dp, time.end, the dt limit '{}'{}",
                     particle_steps, limit, subcycles > 1 ? " and coupling.subcycles" : "");
  return s;
}

int resolve_subcycles(const int requested, const Real dt_fluid, const Real dt_solid) {
  return choose_subcycles(requested, dt_fluid, dt_solid).n;
}

RunSummary run_case(const CaseSpec& spec, Scene scene, const RunSettings& settings, MPI_Comm comm) {
  RunLoop loop(spec, scene, settings, comm);
  return loop.run();
}

std::string format_summary(const RunSummary& s) {
  const double other = std::max(0.0, s.wall_seconds - s.t_fluid - s.t_solid - s.t_coupling - s.t_output);
  const double wall = std::max(1e-12, s.wall_seconds);
  const std::string coupling =
      s.t_coupling > 0 ? fmt::format("coupling {:.2f} s ({:.0f} %), ", s.t_coupling, 100 * s.t_coupling / wall) : "";
  std::string text = fmt::format(
      "run summary: {} steps to t = {:.6g} s in {} wall ({:.3f} s)\n"
      "  fluid {:.2f} s ({:.0f} %), solid {:.2f} s ({:.0f} %), {}output {:.2f} s ({:.0f} %), other {:.2f} s\n"
      "  peak memory {:.1f} MiB",
      s.n_steps, s.end_time, format_duration(s.wall_seconds), s.wall_seconds, s.t_fluid, 100 * s.t_fluid / wall,
      s.t_solid, 100 * s.t_solid / wall, coupling, s.t_output, 100 * s.t_output / wall, other,
      static_cast<double>(s.peak_memory_kib) / 1024);
  if (s.n_ranks > 1)
    text += fmt::format("\n  {} ranks: {} to {} particles owned, {} partition(s), owners and ghosts {:.2f} s", s.n_ranks,
                        s.owned_min, s.owned_max, s.n_partitions, s.t_halo);
  if (s.last_subcycles > 1) text += fmt::format("\n  subcycles {} (solid dt {:.3e} s)", s.last_subcycles, s.last_solid_dt);
  if (s.n_subcycles_raised > 0)
    text += fmt::format("\n  the requested subcycles were raised to the solid's limit in {} step(s)", s.n_subcycles_raised);
  if (s.dt_min > 0) {
    text += fmt::format("\n  smallest dt {:.3e} s at t = {:.6g} s ({}); steps by limit:", s.dt_min, s.t_of_dt_min,
                        s.limit_of_dt_min);
    for (const auto& [name, n] : s.steps_by_limit) text += fmt::format(" {} {}", name, n);
  }
  if (s.coupling_windows > 0)
    text += fmt::format("\n  implicit coupling: {:.2f} iterations per step (at most {}), {} step(s) not converged",
                        static_cast<double>(s.coupling_iterations) / static_cast<double>(s.coupling_windows),
                        s.coupling_iterations_max, s.n_unconverged);
  if (s.n_put_back > 0)
    text += fmt::format("\n  {} time(s) a fluid particle ended a step inside a wall and was put back on its surface",
                        s.n_put_back);
  if (s.n_removed > 0) text += fmt::format("\n  {} fluid particles left the domain and were removed", s.n_removed);
  text += "\n  series " + s.pvd_path;
  return text;
}

}  // namespace mpsfsi
