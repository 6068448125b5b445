// What a run reports as it goes (coupling/run_report.hpp), and the text of its summary.
#include "coupling/run_report.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace mpsfsi {

namespace {

/// Wall time above which a run's projection is called absurd (a week).
constexpr double absurd_wall_seconds = 7 * 24 * 3600.0;

}  // namespace

std::string format_duration(const double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const auto t = static_cast<long>(s + 0.5);
  if (t >= 3600) return fmt::format("{}h{:02d}m", t / 3600, static_cast<int>((t % 3600) / 60));
  if (t >= 60) return fmt::format("{}m{:02d}s", t / 60, static_cast<int>(t % 60));
  return fmt::format("{}s", t);
}

RunReport::RunReport(RunLog& log, const CaseSpec& spec, const RunSettings& settings, const RunParts parts,
                     MPI_Comm comm)
    : log_(log), spec_(spec), settings_(settings), parts_(parts), comm_(comm) {
  MPI_Comm_rank(comm, &rank_);
  MPI_Comm_size(comm, &n_ranks_);
}

void RunReport::projection(const ParticleSet& particles, const Real t) {
  const RunProjection r = project_run(spec_, particles, t, comm_);  // counts summed over the ranks (a collective)
  log_.print(r.text());
}

void RunReport::measured_projection(const RunPosition& at, const Clock::time_point start) {
  if (rank_ != 0 || !(at.dt > 0)) return;
  const double wall = seconds_since(start);
  const double steps = static_cast<double>(at.step - at.step_begin);
  const double remaining_steps = (spec_.time.end - at.t) / at.dt;
  const double remaining_wall = wall / steps * remaining_steps;
  log_.event(fmt::format("{{\"event\":\"projection\",\"step\":{},\"remaining_steps\":{:.4g},\"remaining_wall\":{:.4g}}}",
                         at.step, remaining_steps, remaining_wall));
  log_.note(fmt::format("projection after {} steps: about {:.3g} more steps at dt {:.3g} s ({}), {} of wall time at "
                        "{:.3g} steps/s",
                        at.step - at.step_begin, remaining_steps, at.dt, at.limit, format_duration(remaining_wall),
                        steps / std::max(wall, 1e-9)));
  if (remaining_wall > absurd_wall_seconds)
    log_.print(fmt::format("warning: at this rate the run needs {} of wall time; it cannot finish in any sensible "
                           "time (coarsen dp, shorten time.end, or look at the dt limit '{}')",
                           format_duration(remaining_wall), at.limit));
}

void RunReport::progress(const RunPosition& at, const RunSummary& summary, const Distribution& distribution,
                         const std::size_t n_owned, const Clock::time_point start, const bool final) {
  const std::size_t step = at.step;
  const bool periodic = step % static_cast<std::size_t>(std::max(1, settings_.log_every)) == 0 || step == 1;
  if (n_ranks_ > 1 && (periodic || final) && step != logged_step_) {
    this->distribution(distribution, n_owned, step);  // a collective: every rank keeps logged_step_
    if (rank_ != 0) logged_step_ = step;
  }
  if (rank_ != 0) return;
  const double wall = seconds_since(start);
  const double rate = wall > 0 ? static_cast<double>(step - at.step_begin) / wall : 0;
  const double frac = spec_.time.end > 0 ? at.t / spec_.time.end : 1;
  // ETA from this session's progress (a restarted run began at t_begin).
  const double done = spec_.time.end > at.t_begin ? (at.t - at.t_begin) / (spec_.time.end - at.t_begin) : 1;
  const double eta = done > 0 ? wall * (1 - done) / done : -1;
  std::string ppe, sub;
  if (parts_.fluid) ppe = fmt::format(", PPE {} it (res {:.1e})", at.fluid.iterations, at.fluid.residual);
  if (parts_.fluid && parts_.solid)
    sub = fmt::format(", subcycles {} (solid dt {:.2e} s)", summary.last_subcycles, summary.last_solid_dt);
  if (parts_.implicit) sub += fmt::format(", coupling {} it (res {:.1e})", at.window.iterations, at.window.residual);
  const std::string line = fmt::format("t = {:.5f} s ({:5.1f} %), step {}, {:.1f} steps/s, ETA {}, dt {:.2e} s ({}){}{}",
                                       at.t, 100 * frac, step, rate, format_duration(eta), at.dt, at.limit, ppe, sub);
  // A step is logged once: the final line of a run that ends on a periodic step is not written again.
  const bool due = (periodic || final) && step != logged_step_;
  if (due) logged_step_ = step;
  log_.progress(line,
                fmt::format("{{\"event\":\"step\",\"step\":{},\"t\":{:.9g},\"dt\":{:.6g},\"limit\":\"{}\","
                            "\"ppe_iterations\":{},\"ppe_solves\":{},\"ppe_residual\":{:.3g},\"put_back\":{},\"subcycles\":{},{}"
                            "\"wall\":{:.3f}}}",
                            step, at.t, at.dt, at.limit, at.fluid.iterations, at.fluid.solves, at.fluid.residual,
                            at.fluid.n_put_back, summary.last_subcycles,
                            parts_.implicit ? fmt::format("\"coupling_iterations\":{},\"coupling_residual\":{:.3g},"
                                                          "\"coupling_converged\":{},",
                                                          at.window.iterations, at.window.residual, at.window.converged)
                                            : std::string(),
                            wall),
                due, final);
}

void RunReport::distribution(const Distribution& distribution, const std::size_t n_owned, const std::size_t step) {
  const DistributionStats& d = distribution.stats();
  unsigned long long owned = n_owned;
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
      step, fmt::join(all, ","), mean > 0 ? largest / mean - 1 : 0.0, d.n_partitions, times[0], times[1], times[2]));
}

void RunReport::summary(const RunSummary& s, const RunPosition& at) {
  if (rank_ != 0) return;
  std::string by_limit;
  for (const auto& [name, n] : s.steps_by_limit)
    by_limit += fmt::format("{}\"{}\":{}", by_limit.empty() ? "" : ",", name, n);
  log_.event(fmt::format(
      "{{\"event\":\"summary\",\"steps\":{},\"t\":{:.9g},\"wall\":{:.3f},\"fluid\":{:.3f},\"solid\":{:.3f},"
      "\"coupling\":{:.3f},\"output\":{:.3f},\"removed\":{},\"put_back\":{},\"subcycles_raised_steps\":{},"
      "\"peak_memory_kib\":{},\"dt_min\":{:.6g},\"t_of_dt_min\":{:.9g},\"limit_of_dt_min\":\"{}\","
      "\"steps_by_limit\":{{{}}}{}}}",
      at.step, at.t, s.wall_seconds, s.t_fluid, s.t_solid, s.t_coupling, s.t_output, s.n_removed, s.n_put_back,
      s.n_subcycles_raised, s.peak_memory_kib, s.dt_min, s.t_of_dt_min, s.limit_of_dt_min, by_limit,
      s.coupling_windows > 0
          ? fmt::format(",\"coupling_iterations\":{},\"coupling_iterations_max\":{},\"coupling_windows\":{},"
                        "\"coupling_unconverged\":{}",
                        s.coupling_iterations, s.coupling_iterations_max, s.coupling_windows, s.n_unconverged)
          : std::string()));
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
    text += fmt::format("\n  {} time(s) a fluid particle ended a step inside a wall and was put back out of it",
                        s.n_put_back);
  if (s.n_removed > 0) text += fmt::format("\n  {} fluid particles left the domain and were removed", s.n_removed);
  text += "\n  series " + s.pvd_path;
  return text;
}

}  // namespace mpsfsi
