// The mpsfsi subcommands: check (validate, count, estimate memory) and run.
#include "app/commands.hpp"

#include "io/case.hpp"
#include "io/scene.hpp"
#include "io/vtk_writer.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "core/interrupt.hpp"
#include "core/output_lock.hpp"
#include "core/version.hpp"
#include "core/wall_motion.hpp"
#include "coupling/checkpoint.hpp"
#include "coupling/rank0.hpp"
#include "coupling/simulation.hpp"
#include "fluid/fluid_solver.hpp"

#include <mpi.h>

#include <climits>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <fstream>
#include <limits>
#include <memory>

namespace mpsfsi {

std::vector<std::string> RunOptions::all_overrides() const {
  std::vector<std::string> o;
  if (end_time) o.push_back(fmt::format("time.end={:.17g}", *end_time));
  if (dp) o.push_back(fmt::format("dp={:.17g}", *dp));
  if (subcycles) o.push_back("coupling.subcycles=" + *subcycles);
  if (coupling) o.push_back("coupling.scheme=" + *coupling);
  o.insert(o.end(), overrides.begin(), overrides.end());
  return o;
}

namespace {

/// The scene of a case, built on every rank. Under mpirun all ranks must take the same decision on the
/// memory, so they compare the case with the smallest MemAvailable any of them read (otherwise one rank
/// could stop and the others go on and wait for it).
Scene build_scene_on_every_rank(const CaseSpec& spec) {
  unsigned long long available = available_memory_bytes().value_or(ULLONG_MAX);
  MPI_Allreduce(MPI_IN_PLACE, &available, 1, MPI_UNSIGNED_LONG_LONG, MPI_MIN, MPI_COMM_WORLD);
  return build_scene(spec, available == ULLONG_MAX ? std::nullopt
                                                   : std::optional<std::size_t>(static_cast<std::size_t>(available)));
}

/// One line on a wall's own motion for `check`: its parts, its timing and the largest speed of its particles over
/// the run (the rigid velocity is affine in the point, so the corners of the particles' bounding box bound it);
/// a table that ends before the run is said.
std::string describe_wall_motion(const CaseSpec& spec, const WallSpec& w, const ParticleSet& p, const int body) {
  const WallMotionSpec& m = w.motion;
  std::vector<std::string> parts;
  using T = WallMotionSpec::Translation;
  using R = WallMotionSpec::Rotation;
  const auto vec = [](const Vec& v) {
    std::string s;
    for (int a = 0; a < dim; ++a) s += fmt::format("{}{:.6g}", a ? ", " : "[", v[a]);
    return s + "]";
  };
  Real table_end = -1;  // the last table row's time from start, when the motion has a table
  switch (m.translation) {
    case T::none: break;
    case T::velocity: parts.push_back(fmt::format("translation at {} m/s", vec(m.velocity))); break;
    case T::sine: parts.push_back(fmt::format("translation sine, amplitude {} m, period {:g} s", vec(m.amplitude), m.period)); break;
    case T::table:
      parts.push_back(fmt::format("translation table along {}, {} rows, tau {:g} to {:g} s", vec(m.direction),
                                  m.table_time.size(), m.table_time.front(), m.table_time.back()));
      table_end = m.table_time.back();
      break;
  }
  switch (m.rotation) {
    case R::none: break;
    case R::sine:
      parts.push_back(fmt::format("rotation sine about {}, amplitude {:.6g} deg, period {:g} s", vec(m.pivot),
                                  m.angle_amplitude * 180 / pi, m.angle_period));
      break;
    case R::table:
      parts.push_back(fmt::format("rotation table about {}, {} rows, tau {:g} to {:g} s", vec(m.pivot), m.angle_time.size(),
                                  m.angle_time.front(), m.angle_time.back()));
      table_end = std::max(table_end, m.angle_time.back());
      break;
  }
  Vec lo = Vec::Constant(std::numeric_limits<Real>::max()), hi = -lo;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.body[i] == body) lo = lo.cwiseMin(p.position[i]), hi = hi.cwiseMax(p.position[i]);
  const WallMotion motion(m);
  Real speed = 0;
  const int n_samples = 4000;
  const Real t_end = std::min(spec.time.end, m.stop);
  for (int k = 0; k <= n_samples && lo[0] <= hi[0]; ++k) {
    const WallMotionState state = motion.at(m.start + (t_end - m.start) * k / n_samples);
    for (int corner = 0; corner < (1 << dim); ++corner) {
      Vec x;
      for (int a = 0; a < dim; ++a) x[a] = (corner >> a & 1) ? hi[a] : lo[a];
      speed = std::max(speed, state.velocity_of(x).norm());
    }
  }
  std::string line = fmt::format("  wall {}: {}; start {:g} s, ramp {:g} s{}; largest speed about {:.3g} m/s", w.name,
                                 fmt::join(parts, ", "), m.start, m.ramp,
                                 std::isfinite(m.stop) ? fmt::format(", stop {:g} s", m.stop) : std::string(), speed);
  if (table_end >= 0 && m.start + table_end < std::min(spec.time.end, m.stop))
    line += fmt::format("; its table ends at t = {:g} s, before the run: the wall stays there after", m.start + table_end);
  for (const auto& b : spec.bodies)
    if (b.clamp_wall == w.name) line += fmt::format("; the clamp of '{}' moves with it", b.name);
  return line;
}

}  // namespace

int command_check(const RunOptions& opts) {
  const CaseSpec spec = load_case(opts.case_file, opts.all_overrides());
  const Scene scene = build_scene_on_every_rank(spec);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return 0;  // under mpirun the report is rank 0's (every rank checked the same case)
  const auto& p = scene.particles;
  fmt::print("case {} ({}): dp = {:g} m, end time {:g} s\n", spec.name, spec.file, spec.dp, spec.time.end);
  fmt::print("{:<20} {:<6} {:>10} {:>10} {:>10} {:>10}\n", "body", "kind", "particles", "wall", "dummy", "clamped");
  for (const auto& c : scene.counts)
    fmt::print("{:<20} {:<6} {:>10} {:>10} {:>10} {:>10}\n", c.name, c.kind, c.n_particles, c.n_wall, c.n_dummy,
               c.n_clamped);
  fmt::print("total: {} particles ({} fluid, {} solid, {} wall, {} dummy)\n", p.size(), p.n_of_kind(ParticleKind::fluid),
             p.n_of_kind(ParticleKind::solid), p.n_of_kind(ParticleKind::wall), p.n_of_kind(ParticleKind::dummy));
  // The region each body's particles represent (their bounding box + dp/2 on each side): the lattice rounds
  // every side of a rectangle to whole particles, so a body can come out longer or shorter than written.
  fmt::print("extent of the bodies (particles + dp/2 on each side):\n");
  std::vector<std::string> warnings;
  // "[x0, x1] x [y0, y1] (x [z0, z1]) m (a x b (x c) m)"
  const auto show_rect = [&](const Rect& r) {
    const auto x = [&](const Real v) { return std::abs(v) < 1e-9 * spec.dp ? Real(0) : v; };  // no round-off "1e-15"
    std::string ranges, sizes;
    for (int a = 0; a < dim; ++a) {
      ranges += fmt::format("{}[{:.6g}, {:.6g}]", a ? " x " : "", x(r.lo[a]), x(r.hi[a]));
      sizes += fmt::format("{}{:.6g}", a ? " x " : "", r.size()[a]);
    }
    return fmt::format("{} m ({} m)", ranges, sizes);
  };
  for (std::size_t k = 0; k < spec.bodies.size() && k < scene.counts.size(); ++k) {
    const BodyCount& c = scene.counts[k];
    std::string line = fmt::format("  {:<20} {}", c.name, show_rect(c.extent));
    if (c.shape_volume)
      line += fmt::format("; {} particles fill {:.6g} m{} against the {}'s {:.6g} ({:+.2f} %{})", c.n_particles,
                          static_cast<double>(c.n_particles) * std::pow(spec.dp, dim), dim == 2 ? "2" : "3", c.shape,
                          *c.shape_volume,
                          100 * (static_cast<double>(c.n_particles) * std::pow(spec.dp, dim) / *c.shape_volume - 1),
                          spec.bodies[k].subtract.empty() ? "" : ", less what is cut out");
    if (c.shape_bounds) line += fmt::format("; the {}'s bounds {} ({})", c.shape, show_rect(*c.shape_bounds), c.shape_source);
    if (c.free_length)
      line += fmt::format("; free length {:.6g} m along {} (file: {:.6g} m)", *c.free_length, "xyz"[c.free_axis],
                          c.file_free_length);
    fmt::print("{}\n", line);
    if (c.extent_difference > 0.25 * spec.dp * (1 + 1e-9))
      warnings.push_back(fmt::format("warning: body '{}' is represented by {}, not by its rectangle {}: a side moves by "
                                     "{:.3g} m, more than dp/4 = {:.3g} m (bodies are filled on the case's lattice of cells dp "
                                     "= {:g} m wide from the tank's corner; sides on it are exact)",
                                     c.name, show_rect(c.extent), show_rect(spec.bodies[k].rect), c.extent_difference,
                                     0.25 * spec.dp, spec.dp));
  }
  for (std::size_t k = spec.bodies.size(); k < scene.counts.size(); ++k) {
    const BodyCount& c = scene.counts[k];
    if (!c.shape_bounds) continue;
    fmt::print("  wall {}: a {} ({}), bounds {}, {} {:.6g} m{}\n", c.name, c.shape, c.shape_source,
               show_rect(*c.shape_bounds), dim == 2 ? "area" : "volume", *c.shape_volume, dim == 2 ? "2" : "3");
  }
  for (std::size_t k = 0; k < spec.walls.size(); ++k)
    if (spec.walls[k].motion.moving())
      fmt::print("{}\n", describe_wall_motion(spec, spec.walls[k], p, static_cast<int>(spec.bodies.size() + k)));
  for (const auto& w : warnings) fmt::print("{}\n", w);
  const double mib = static_cast<double>(estimate_memory_bytes(spec, scene)) / (1024.0 * 1024.0);
  fmt::print("memory estimate: {:.1f} MiB of data, about {:.0f} MiB with the program\n", mib,
             mib + static_cast<double>(program_bytes) / (1024.0 * 1024.0));
  fmt::print("{}\n", project_run(spec, p).text());
  if (!opts.output.empty()) {
    VtkSeriesWriter writer(opts.output, "particles");
    const auto path = writer.write(p, 0.0);
    fmt::print("initial particles written to {} (series {})\n", path, writer.pvd_path());
  }
  fmt::print("case OK\n");
  return 0;
}

namespace {

/// The output folder of a new run: refused (CaseError) if it is not a folder, cannot be created, or holds files
/// and `overwrite` is false; else created if missing and locked by `lock` (which throws if another run holds it).
void prepare_output_folder(const std::string& out, const bool overwrite, const std::function<void()>& lock) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(out, ec);
  if (fs::exists(st)) {
    if (!fs::is_directory(st))
      throw CaseError(fmt::format("--output {}: exists and is not a folder; expected a new or empty folder", out));
    const bool empty = fs::is_empty(out, ec);
    if (ec)
      throw CaseError(fmt::format("--output {}: cannot read the folder: {}; expected a folder this user can write", out,
                                  ec.message()));
    if (!empty && !holds_only_lock(out) && !overwrite)
      throw CaseError(fmt::format("--output {}: the folder exists and is not empty; choose another or pass --overwrite", out));
    lock();  // a refused run leaves no lock file behind
    return;
  }
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out, ec))
    throw CaseError(fmt::format("--output {}: cannot create the folder: {}; expected a path where this user can make a "
                                "folder",
                                out, ec ? ec.message() : std::string("not a folder")));
  lock();
}

/// The case of a restart: the case file if given, else the one stored in the checkpoint; either way with
/// the command line's overrides. Refused unless it equals the checkpoint's case outside the keys a restart
/// may change, and unless the checkpoint lies before the end time. `note`: the numerical controls it changes.
CaseSpec restart_case(const RunOptions& opts, const Checkpoint& ck, std::string& note) {
  const CheckpointInfo& info = ck.info;
  CaseSpec spec = opts.case_file.empty()
                      ? parse_case(info.resolved_yaml, info.case_file, opts.all_overrides(), info.case_dir)
                      : load_case(opts.case_file, opts.all_overrides());
  std::vector<CaseDifference> strict, tuned;
  for (auto& d : case_differences(info.resolved_yaml, spec.resolved_yaml))
    (key_under(d.key, restart_tunable_keys()) ? tuned : strict).push_back(std::move(d));
  const auto listing = [](const std::vector<CaseDifference>& diffs) {
    std::string list;
    for (std::size_t k = 0; k < diffs.size() && k < 8; ++k) list += "\n  " + diffs[k].text();
    if (diffs.size() > 8) list += fmt::format("\n  ... and {} more", diffs.size() - 8);
    return list;
  };
  if (!strict.empty())
    throw CaseError(fmt::format("--restart {}: the checkpoint was written for case '{}' ({}); this run's case '{}' ({}) "
                                "differs (checkpoint vs this run):{}\nA restart may change only {}, and the numerical "
                                "controls {}.",
                                ck.path, info.case_name, info.case_file, spec.name, spec.file, listing(strict),
                                fmt::join(restart_free_keys(), ", "), fmt::join(restart_tunable_keys(), ", ")));
  if (!tuned.empty())
    note = fmt::format("note: this restart changes numerical controls of the checkpoint's run (checkpoint vs this "
                       "run):{}\nso it continues that run otherwise than the original did (not bit for bit)\n",
                       listing(tuned));
  const Real eps = 1e-12 * std::max<Real>(1, spec.time.end);
  if (!(info.time < spec.time.end - eps))
    throw CaseError(fmt::format("--restart {}: the checkpoint is at t = {:.9g} s, not before the end time {:.9g} s; "
                                "pass a later --end-time",
                                ck.path, info.time, spec.time.end));
  return spec;
}

}  // namespace

int command_run(const RunOptions& opts, const std::string& command_line) {
  int rank = 0, n_ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &n_ranks);
  namespace fs = std::filesystem;
  std::unique_ptr<Checkpoint> ck;
  if (!opts.restart.empty()) ck = std::make_unique<Checkpoint>(read_checkpoint(opts.restart, MPI_COMM_WORLD));
  else if (opts.case_file.empty()) throw CaseError("run: a case file is required (or --restart CHECKPOINT)");
  std::string note;
  const CaseSpec spec = ck ? restart_case(opts, *ck, note) : load_case(opts.case_file, opts.all_overrides());
  Scene scene = build_scene_on_every_rank(spec);
  std::string out = opts.output;
  if (out.empty()) {
    const std::string ck_dir = ck ? fs::path(ck->path).parent_path().string() : std::string();
    out = ck ? (ck_dir.empty() ? std::string(".") : ck_dir) : "out/" + spec.name;
  }
  RunSettings settings;
  settings.output_dir = out;
  settings.quiet = opts.quiet;
  settings.checkpoint_every = opts.checkpoint_every.value_or(0);
  settings.checkpoint_keep = opts.checkpoint_keep;
  settings.max_steps = opts.max_steps;
  settings.restart = ck.get();
  bool continuing = false;
  std::vector<std::string> removed;
  // The output folder is locked (rank 0) for the run's life: a second run into it is refused.
  std::unique_ptr<OutputLock> lock;
  const auto take_lock = [&] {
    try {
      lock = std::make_unique<OutputLock>(out);
    } catch (const OutputLocked& e) {
      throw CaseError(fmt::format("--output {}: {}", out, e.what()));
    }
  };
  on_rank0(MPI_COMM_WORLD, [&] {
    if (ck) {
      const RestartOutputs r = prepare_restart_outputs(out, ck->info, opts.overwrite, take_lock);
      continuing = r.continuing;
      settings.append_files = r.appended;
      removed = r.removed;
    } else {
      prepare_output_folder(out, opts.overwrite, take_lock);
    }
    write_file_atomically(out + "/case.resolved.yaml", spec.resolved_yaml + "\n", "resolved case");
    const std::string command_path = out + "/command.txt";
    std::ofstream command(command_path, continuing ? std::ios::app : std::ios::trunc);
    command << command_line << "\n";
    command.flush();
    check_written(command, command_path, "command line");
  });
  settings.continue_series = continuing;
  settings.output_lock = lock.get();
  if (rank == 0 && !opts.quiet) {
    fmt::print("mpsfsi {}: case {} ({} particles), end time {:g} s, output {}\n", version_and_dimension(), spec.name,
               scene.particles.size(), spec.time.end, out);
    if (const auto& lw = spec.fluid.lateral_walls; lw.gap > 0 && !spec.fluid_materials.empty())
      fmt::print("fluid: lateral-wall friction ({}, gap {:g} m{}): velocity relative to the tank decays at k = {:.4g} 1/s\n",
                 to_string(lw.model), lw.gap, lw.model == LateralWallModel::stokes ? fmt::format(", {:.4g} Hz", lw.frequency) : std::string(),
                 lateral_wall_friction_rate(lw, spec.fluid_materials.front().nu));
    if (spec.solid.wide_plate)
      for (const auto& m : spec.solid_materials)
        fmt::print("solid: {} as a wide plate, plane stress with E / (1 - nu^2) = {:.4g} Pa (E = {:.4g} Pa)\n", m.name,
                   spec.solid.modulus(m), m.E);
    if (ck) {
      fmt::print("restart from {} (t = {:.9g} s, step {}, written {}); {}\n", ck->path, ck->info.time, ck->info.step,
                 ck->info.written_at,
                 continuing ? "continuing the folder's outputs after the checkpoint time"
                            : "new output files from the checkpoint time");
      if (ck->info.n_ranks != n_ranks)
        fmt::print("note: the checkpoint was written on {} rank(s), this run has {}: the pressure solve is split "
                   "otherwise, so the run continues correctly but not bit for bit as the original would have\n",
                   ck->info.n_ranks, n_ranks);
    }
  }
  if (rank == 0 && !note.empty()) fmt::print("{}", note);  // also with --quiet: the run is not the original's
  if (rank == 0 && !removed.empty()) {  // also with --quiet: files were deleted
    std::string list;
    for (std::size_t k = 0; k < removed.size() && k < 6; ++k) list += (k ? ", " : "") + removed[k];
    if (removed.size() > 6) list += fmt::format(" and {} more", removed.size() - 6);
    fmt::print("note: the restart continues the folder from t = {:.9g} s; its {} later file(s) of the earlier "
               "trajectory were removed: {}\n",
               ck->info.time, removed.size(), list);
  }
  install_interrupt_handlers();  // Ctrl-C / SIGTERM: stop at the end of the step (core/interrupt.hpp)
  try {
    const RunSummary s = run_case(spec, std::move(scene), settings, MPI_COMM_WORLD);
    if (rank == 0) fmt::print("{}\n", format_summary(s));
    if (s.interrupted_by != 0) {
      if (rank == 0)
        fmt::print(stderr, "mpsfsi: run interrupted by {} at t = {:.9g} s (step {}); frame and checkpoint written. "
                           "Continue with: mpsfsi run --restart {}\n",
                   signal_name(s.interrupted_by), s.end_time, s.n_steps, out);
      return 128 + s.interrupted_by;
    }
  } catch (const RunFailure& e) {
    fmt::print(stderr, "mpsfsi: run stopped: {}\n", e.what());
    return 3;
  }
  return 0;
}

}  // namespace mpsfsi
