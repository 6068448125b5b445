// The run loop: per step the time-step policy's dt (coupling/time_step_policy.hpp), the fluid step, the
// solid's sub-steps or the coupled window (coupling/coupling_scheme.hpp), and the state checks
// (coupling/state_guard.hpp); frames, probes and receivers on their schedules (coupling/run_output.hpp); the
// progress and the summary (coupling/run_report.hpp); checkpoints and restarts (the run loop's own state plus
// each participant's save_state / load_state, in named sections; coupling/checkpoint.hpp). On several ranks
// the particles are distributed (core/distribution.hpp): each rank steps, checks and writes (one piece per
// frame) its owned particles, and checkpoints gather the state by global id on rank 0; fluid, solid and
// coupling each renew owners and ghosts when they need them.
#include "coupling/simulation.hpp"

#include "core/distribution.hpp"
#include "core/files.hpp"
#include "core/interrupt.hpp"
#include "core/stopwatch.hpp"
#include "coupling/checkpoint.hpp"
#include "coupling/coupling_scheme.hpp"
#include "coupling/fsi_interface.hpp"
#include "core/collectives.hpp"
#include "coupling/rank0.hpp"
#include "coupling/run_log.hpp"
#include "coupling/run_output.hpp"
#include "coupling/run_report.hpp"
#include "coupling/state_guard.hpp"
#include "coupling/time_step_policy.hpp"

#include "fluid/fluid_solver.hpp"
#include "solid/solid_solver.hpp"

#include <fmt/format.h>

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <deque>
#include <filesystem>
#include <memory>

namespace mpsfsi {

namespace {

long peak_memory_kib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

/// The run: its participants, the step (the time-step policy, the coupled window, the state checks), the
/// outputs and checkpoints on their schedules, the reports.
class RunLoop {
 public:
  RunLoop(const CaseSpec& spec, Scene& scene, const RunSettings& settings, MPI_Comm comm)
      : spec_(spec), p_(scene.particles), settings_(settings), comm_(comm),
        step_policy_({spec.time.end, spec.solid.dt, spec.coupling.subcycles}, comm),
        output_(spec, scene.particles, settings, comm), log_(output_.log()), guard_(spec, scene.particles, comm) {
    MPI_Comm_rank(comm, &rank_);
    MPI_Comm_size(comm, &n_ranks_);
    // The scene is whole on every rank here: distribute it.
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
      solid_->set_output_directory(settings.output_dir, appends(settings, "fragments.csv"));
    }
    if (fluid_ && solid_) {
      FsiOptions fo;
      fo.load_relaxation = spec.coupling.load_relaxation;
      solid_->set_damping(spec.coupling.solid_damping);
      coupling_ = std::make_unique<FsiInterface>(spec, p_, fo, dist_.get());
      coupling_->initialize();
      scheme_ = make_coupling_scheme(spec.coupling, CouplingParticipants{spec.dp, p_, *dist_, *fluid_, *solid_, *coupling_});
      on_rank0(comm, [&] {
        coupling_->open_csv(settings.output_dir + "/interface.csv", appends(settings, "interface.csv"));
      });
    }
    output_.select_fields(p_);
    summary_.pvd_path = output_.series().pvd_path();
    report_ = std::make_unique<RunReport>(
        log_, spec, settings, RunParts{fluid_ != nullptr, solid_ != nullptr, scheme_ && scheme_->name() == "implicit"},
        comm);
    if (settings.restart) load_checkpoint(*settings.restart);
  }

  RunSummary run() {
    const auto t_start = Clock::now();
    at_.t_begin = at_.t;
    at_.step_begin = at_.step;
    if (!settings_.restart) {
      write_output();
      output_.record_initial_rows(p_, at_.t);
    }
    report_->projection(p_, at_.t);
    const Real eps = 1e-12 * std::max<Real>(1, spec_.time.end);
    const Real every = settings_.checkpoint_every;
    const auto next_checkpoint_after = [&](const Real t) { return (std::floor((t + eps) / every) + 1) * every; };
    Real next_checkpoint = every > 0 ? next_checkpoint_after(at_.t) : 0;
    Real last_checkpoint = settings_.restart ? at_.t : -1;
    const auto more_steps = [&] { return settings_.max_steps == 0 || at_.step - at_.step_begin < settings_.max_steps; };
    Real last_frame = at_.t;
    while (at_.t < spec_.time.end - eps && more_steps() && !interrupted()) {
      guard_.keep_last_good(at_.t, at_.step);
      step();
      output_.record_rows(p_, at_.t);
      report_->progress(at_, summary_, *dist_, p_.n_owned(), t_start, false);
      if (at_.step - at_.step_begin == 20) report_->measured_projection(at_, t_start);
      if (output_.frame_due(at_.t)) {
        write_output();
        last_frame = at_.t;
        output_.frame_written(at_.t);
      }
      if (every > 0 && at_.t >= next_checkpoint - eps) {
        write_checkpoint_now();
        last_checkpoint = at_.t;
        next_checkpoint = next_checkpoint_after(at_.t);
      }
    }
    // The state reached is always the last frame: at an end time between two output times, after --max-steps
    // or a signal.
    if (last_frame != at_.t) write_output();
    // The end state, to extend the run; after a signal always, to continue it.
    if ((every > 0 || summary_.interrupted_by != 0) && last_checkpoint != at_.t) write_checkpoint_now();
    report_->progress(at_, summary_, *dist_, p_.n_owned(), t_start, true);
    if (summary_.interrupted_by != 0)
      log_.event(fmt::format("{{\"event\":\"interrupted\",\"signal\":\"{}\",\"step\":{},\"t\":{:.9g}}}",
                             signal_name(summary_.interrupted_by), at_.step, at_.t));
    summary_.n_steps = at_.step;
    summary_.end_time = at_.t;
    summary_.t_output = output_.seconds();
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
    report_->summary(summary_, at_);
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

  void step() {
    const StepPlan plan = step_policy_.plan(at_.t, fluid_.get(), solid_.get());
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
                              at_.step + 1, spec_.coupling.subcycles, dt / spec_.coupling.subcycles,
                              plan.solid_stable_dt, n_sub));
      raised_said_ = true;
    }
    ++summary_.steps_by_limit[limit];
    if (limit != "end time" && (summary_.dt_min == 0 || dt < summary_.dt_min)) {
      summary_.dt_min = dt;
      summary_.t_of_dt_min = at_.t;
      summary_.limit_of_dt_min = limit;
    }
    if (n_ranks_ > 1 && at_.step % repartition_every == 0) {
      const auto t0 = Clock::now();
      const std::vector<Real> w = work_weights(p_.n_owned());
      if (dist_->imbalance(p_, w) > dist_->settings().imbalance_threshold) dist_->partition(p_, w);
      summary_.t_fluid += seconds_since(t0);
    }
    std::string window_finding;  // the implicit coupling's verdict, the same on every rank
    try {
      if (scheme_) {  // fluid, load, solid: coupling/coupling_scheme.hpp
        const CouplingWindow w = scheme_->advance(at_.t, dt, n_sub);
        at_.fluid = w.fluid;
        summary_.t_fluid += w.t_fluid;
        summary_.t_solid += w.t_solid;
        summary_.t_coupling += w.t_coupling;
        window_finding = note_window(w);
      } else if (fluid_) {
        const auto t0 = Clock::now();
        at_.fluid = fluid_->advance(at_.t, dt);
        summary_.t_fluid += seconds_since(t0);
      } else if (solid_) {
        const auto t0 = Clock::now();
        const Real dts = dt / n_sub;
        for (int k = 0; k < n_sub; ++k) solid_->advance(at_.t + k * dts, dts);
        summary_.t_solid += seconds_since(t0);
      }
      if (fluid_) {
        summary_.n_removed += at_.fluid.n_removed;
        summary_.n_put_back += at_.fluid.n_put_back;
        if (at_.fluid.n_removed > 0)
          log_.note(fmt::format("step {}: {} fluid particle(s) left the domain and were removed ({} so far)",
                                at_.step + 1, at_.fluid.n_removed, summary_.n_removed));
      }
    } catch (const RunFailure& e) {
      fail_within_step(e.what());
    } catch (const std::exception& e) {
      fail_within_step(fmt::format("step {} (t = {:.6g} s): {}", at_.step + 1, at_.t, e.what()));
    }
    // The state checks: each rank looks at its particles, the first finding stops every rank.
    std::string finding = window_finding;
    if (finding.empty()) {  // (the window's verdict is every rank's: all skip the checks alike)
      try {
        guard_.check(at_.step + 1, at_.t + dt);
        if (at_.fluid.n_removed > 0) guard_.check_losses(at_.step + 1, at_.t + dt, at_.fluid.dt, step_limit_);
      } catch (const RunFailure& e) {
        finding = e.what();
      }
    }
    finding = agreed_message(comm_, finding);
    if (!finding.empty()) fail(finding);
    at_.t += dt;
    ++at_.step;
    at_.dt = dt;
    at_.limit = limit;
    summary_.last_subcycles = n_sub;
    summary_.last_solid_dt = dt / n_sub;
  }

  /// The implicit coupling's iterations of the window into the summary; a window that did not converge is
  /// said once and counted, or (coupling.implicit.on_max_iterations: stop) returned as the finding that stops
  /// the run (every rank has the same verdict: the residual is reduced over the ranks).
  std::string note_window(const CouplingWindow& w) {
    at_.window = w;
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
        at_.step + 1, at_.t, ic.max_iterations, w.residual, ic.tolerance);
    if (ic.on_max_iterations == NonConvergence::stop)
      return what + "; coupling.implicit.on_max_iterations = stop (raise max_iterations, loosen the tolerance, or "
                    "choose another acceleration)";
    if (!unconverged_said_)
      log_.note(what + "; the run goes on with the last iterate (said once; the summary counts such steps)");
    unconverged_said_ = true;
    return {};
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
    const std::string frame = output_.write_failure_frame(guard_.last_good(), guard_.last_good_t());
    log_.event(fmt::format("{{\"event\":\"failure\",\"step\":{},\"t\":{:.9g},\"diagnosis\":\"{}\"}}", at_.step + 1,
                           at_.t, RunLog::json_escape(diagnosis)));
    log_.end_line();
    throw RunFailure(fmt::format("{}\nlast good frame (t = {:.6g} s, after step {}): {}", diagnosis,
                                 guard_.last_good_t(), guard_.last_good_step(), frame));
  }

  /// A frame at the current time, with the solid's derived fields and fragments.csv (written by rank 0 once
  /// every rank is past the collectives) and the interface table.
  void write_output() {
    if (solid_) on_every_rank(comm_, [&] { solid_->prepare_output(at_.t); });
    output_.write_frame(p_, at_.t, at_.step, [&] {
      if (coupling_) coupling_->write_csv(at_.t);
    });
  }

  /// The run loop's own state: everything that decides the coming steps and outputs.
  void save_run_state(BinaryWriter& w) {
    w.section("run");
    w.f64(at_.t);
    w.u64(at_.step);
    w.f64(at_.dt);
    w.string(at_.limit);
    w.f64(output_.schedule().next_frame);
    w.f64(output_.schedule().next_probe);
    w.u64(summary_.n_removed);
    w.u64(summary_.n_put_back);
    w.u64(summary_.n_subcycles_raised);
    w.i64(summary_.last_subcycles);
    w.f64(summary_.last_solid_dt);
    w.boolean(raised_said_);
    w.i64(at_.fluid.iterations);
    w.f64(at_.fluid.residual);
    w.boolean(fluid_ != nullptr);
    w.boolean(solid_ != nullptr);
    w.boolean(coupling_ != nullptr);
    output_.receivers().save_state(w);
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
        output_.check_folder();
        write_checkpoint_on_rank0(all, distribution, scheme);
      });
    } catch (const OutputError& e) {
      throw OutputError(output_.stopped_by_output(e.what(), at_.t, at_.step));
    }
  }

  void write_checkpoint_on_rank0(const ParticleSet& all, const BinaryWriter& distribution, const BinaryWriter& scheme) {
    const auto t0 = Clock::now();
    BinaryWriter w;
    save_run_state(w);
    all.save_state(w);
    w.bytes() += distribution.bytes();
    for (const Participant* q : participants()) q->save_state(w);
    if (coupling_) coupling_->save_state(w);
    w.bytes() += scheme.bytes();
    w.section("end");
    output_.receivers().flush();
    CheckpointInfo info;
    info.case_name = spec_.name;
    info.case_file = spec_.file;
    std::error_code ec;
    const auto dir = std::filesystem::absolute(std::filesystem::path(spec_.file).parent_path(), ec);
    info.case_dir = ec ? std::string(".") : dir.lexically_normal().string();
    info.resolved_yaml = spec_.resolved_yaml;
    info.time = at_.t;
    info.step = at_.step;
    info.n_particles = all.size();
    info.n_ranks = n_ranks_;
    info.next_frame = output_.series().next_frame();
    info.frames = output_.series().frames();
    info.outputs = mark_outputs(settings_.output_dir, {"probes.csv", "interface.csv", "fragments.csv", "receivers.csv", "run.jsonl"});
    const std::time_t now = std::time(nullptr);
    char date[64] = "";
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S %z", std::localtime(&now));
    info.written_at = date;
    const std::string path = (std::filesystem::path(settings_.output_dir) / checkpoint_file_name(at_.t)).string();
    write_checkpoint(path, info, w.bytes());
    log_.event(fmt::format("{{\"event\":\"checkpoint\",\"step\":{},\"t\":{:.9g},\"file\":\"{}\"}}", at_.step, at_.t,
                           RunLog::json_escape(path)));
    log_.note(fmt::format("checkpoint at t = {:.6g} s (step {}): {} ({:.1f} MiB)", at_.t, at_.step, path,
                          static_cast<double>(w.bytes().size()) / (1024.0 * 1024.0)));
    written_.push_back(path);
    while (settings_.checkpoint_keep > 0 && written_.size() > static_cast<std::size_t>(settings_.checkpoint_keep)) {
      if (written_.front() != path) std::filesystem::remove(written_.front(), ec);
      written_.pop_front();
    }
    output_.seconds() += seconds_since(t0);
  }

  /// Restart: the state of the checkpoint replaces the initial one (the solvers were built from the
  /// initial scene, which gave them their reference data).
  void load_checkpoint(const Checkpoint& c) {
    BinaryReader in = c.payload();
    bool exact = true;  // the coming steps are bit for bit the original run's
    try {
      in.expect_section("run");
      at_.t = in.f64("the time");
      at_.step = in.u64("the step");
      at_.dt = in.f64("the time step");
      at_.limit = in.string("the time-step limit");
      output_.schedule().next_frame = in.f64("the next output time");
      output_.schedule().next_probe = in.f64("the next probe time");
      summary_.n_removed = in.u64("the removed count");
      summary_.n_put_back = in.u64("the put-back count");
      summary_.n_subcycles_raised = in.u64("the raised-subcycles count");
      summary_.last_subcycles = static_cast<int>(in.i64("the subcycles"));
      summary_.last_solid_dt = in.f64("the solid time step");
      raised_said_ = in.boolean("a log flag");
      at_.fluid.iterations = static_cast<int>(in.i64("the pressure-solve iterations"));
      at_.fluid.residual = in.f64("the pressure-solve residual");
      const bool fluid = in.boolean("the fluid flag"), solid = in.boolean("the solid flag"),
                 coupled = in.boolean("the coupling flag");
      if (fluid != (fluid_ != nullptr) || solid != has_solid_ || coupled != (has_solid_ && fluid_ != nullptr))
        in.fail("the checkpoint's run has other participants (fluid, solid, coupling) than this case");
      output_.receivers().load_state(in);
      p_.drop_ghosts();
      p_.load_state(in);  // every particle, on every rank
      dist_->load_state(in, p_);
      for (Participant* q : participants()) exact = q->load_state(in) && exact;
      if (coupling_) coupling_->load_state(in);
      if (scheme_) scheme_->load_state(in);
      in.expect_section("end");
      if (!in.at_end()) in.fail("unexpected data after the state");
    } catch (const StateFormatError& e) {
      throw CaseError(std::string("checkpoint ") + e.what());
    }
    if (!exact)
      log_.print("note: the pressure preconditioner the checkpoint's run kept between setups "
                 "(fluid.preconditioner_rebuild_every > 1) cannot be rebuilt here (it was saved on several ranks, or "
                 "the setting changed) and is set up anew: the continuation agrees with the original run to the "
                 "solver tolerance, not bit for bit");
    if (c.info.n_ranks != n_ranks_)
      log_.print(fmt::format("note: the checkpoint was written on {} rank(s), this run has {}: the particles are "
                             "partitioned anew and the continuation agrees with the original run to the solver "
                             "tolerance, not bit for bit",
                             c.info.n_ranks, n_ranks_));
    output_.continue_series(at_.t, c.info.next_frame);
    log_.event(fmt::format("{{\"event\":\"restart\",\"step\":{},\"t\":{:.9g},\"checkpoint\":\"{}\"}}", at_.step, at_.t,
                           RunLog::json_escape(c.path)));
  }

  /// The run's participants (the fluid, the solid, or both in that order), as the checkpoint holds them.
  std::vector<Participant*> participants() const {
    std::vector<Participant*> all;
    if (fluid_) all.push_back(fluid_.get());
    if (solid_) all.push_back(solid_.get());
    return all;
  }

  /// The partition weights of the first n particles: their work in a fluid step (fluid_work_weights; solid
  /// particles 1).
  std::vector<Real> work_weights(const std::size_t n) const { return fluid_work_weights(p_, n, comm_); }

  /// Steps between checks of the owned work's balance (re-partition above the threshold).
  static constexpr std::size_t repartition_every = 20;

  const CaseSpec& spec_;
  ParticleSet& p_;
  const RunSettings& settings_;
  MPI_Comm comm_;
  int rank_ = 0;
  int n_ranks_ = 1;
  TimeStepPolicy step_policy_;
  RunOutput output_;  ///< frames, probes, receivers, the run log (makes the output folder)
  RunLog& log_;       ///< output_'s
  StateGuard guard_;  ///< the state checks and the last good state
  std::unique_ptr<RunReport> report_;
  std::unique_ptr<Distribution> dist_;
  std::unique_ptr<FluidSolver> fluid_;
  std::unique_ptr<SolidSolver> solid_;
  std::unique_ptr<FsiInterface> coupling_;
  std::unique_ptr<CouplingScheme> scheme_;
  bool has_solid_ = false;             ///< the case has a solid
  RunPosition at_;                     ///< where the run is: time, step, dt and its limit, the last fluid step
  std::string step_limit_ = "-";       ///< the dt limit of the step being taken
  bool unconverged_said_ = false;
  bool raised_said_ = false;
  RunSummary summary_;
  std::deque<std::string> written_;    ///< checkpoints this run wrote, oldest first
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

}  // namespace mpsfsi
