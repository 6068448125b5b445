// The mpsfsi subcommands: check (validate, count, estimate memory) and run.
#include "app/commands.hpp"

#include "io/case.hpp"
#include "io/scene.hpp"
#include "io/vtk_writer.hpp"

#include <fmt/format.h>

#include "coupling/simulation.hpp"

#include <mpi.h>

#include <filesystem>
#include <fstream>

namespace mpsfsi {

std::vector<std::string> RunOptions::all_overrides() const {
  std::vector<std::string> o;
  if (end_time) o.push_back(fmt::format("time.end={:.17g}", *end_time));
  if (dp) o.push_back(fmt::format("dp={:.17g}", *dp));
  if (subcycles) o.push_back("coupling.subcycles=" + *subcycles);
  o.insert(o.end(), overrides.begin(), overrides.end());
  return o;
}

int command_check(const RunOptions& opts) {
  const CaseSpec spec = load_case(opts.case_file, opts.all_overrides());
  const Scene scene = build_scene(spec);
  const auto& p = scene.particles;
  fmt::print("case {} ({}): dp = {:g} m, end time {:g} s\n", spec.name, spec.file, spec.dp, spec.time.end);
  fmt::print("{:<20} {:<6} {:>10} {:>10} {:>10} {:>10}\n", "body", "kind", "particles", "wall", "dummy", "clamped");
  for (const auto& c : scene.counts)
    fmt::print("{:<20} {:<6} {:>10} {:>10} {:>10} {:>10}\n", c.name, c.kind, c.n_particles, c.n_wall, c.n_dummy,
               c.n_clamped);
  fmt::print("total: {} particles ({} fluid, {} solid, {} wall, {} dummy)\n", p.size(), p.n_of_kind(ParticleKind::fluid),
             p.n_of_kind(ParticleKind::solid), p.n_of_kind(ParticleKind::wall), p.n_of_kind(ParticleKind::dummy));
  const double mib = static_cast<double>(estimate_memory_bytes(spec, scene)) / (1024.0 * 1024.0);
  fmt::print("memory estimate: {:.1f} MiB\n", mib);
  if (!opts.output.empty()) {
    VtkSeriesWriter writer(opts.output, "particles");
    const auto path = writer.write(p, 0.0);
    fmt::print("initial particles written to {} (series {})\n", path, writer.pvd_path());
  }
  fmt::print("case OK\n");
  return 0;
}

int command_run(const RunOptions& opts, const std::string& command_line) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const CaseSpec spec = load_case(opts.case_file, opts.all_overrides());
  Scene scene = build_scene(spec);
  const std::string out = opts.output.empty() ? "out/" + spec.name : opts.output;
  namespace fs = std::filesystem;
  if (rank == 0) {
    if (fs::exists(out) && !fs::is_empty(out) && !opts.overwrite)
      throw CaseError(fmt::format("--output {}: the folder exists and is not empty; choose another or pass --overwrite", out));
    fs::create_directories(out);
    std::ofstream(out + "/case.resolved.yaml") << spec.resolved_yaml << "\n";
    std::ofstream(out + "/command.txt") << command_line << "\n";
  }
  MPI_Barrier(MPI_COMM_WORLD);
  RunSettings settings;
  settings.output_dir = out;
  settings.quiet = opts.quiet;
  if (rank == 0 && !opts.quiet)
    fmt::print("mpsfsi {}: case {} ({} particles), end time {:g} s, output {}\n", MPSFSI_VERSION, spec.name,
               scene.particles.size(), spec.time.end, out);
  try {
    const RunSummary s = run_case(spec, std::move(scene), settings, MPI_COMM_WORLD);
    if (rank == 0) fmt::print("{}\n", format_summary(s));
  } catch (const RunFailure& e) {
    fmt::print(stderr, "mpsfsi: run stopped: {}\n", e.what());
    return 3;
  }
  return 0;
}

}  // namespace mpsfsi
