// The mpsfsi program: `mpsfsi check CASE` validates a case and prints its particle counts and memory
// estimate; `mpsfsi run CASE` runs it. Exit codes: 0 success, 2 bad input (case file or command
// line), 3 a run that went wrong (diagnosis printed), 4 an output file could not be written (disk full,
// permissions; the files written before are complete), 1 an internal error, 128 + the signal (130 SIGINT,
// 143 SIGTERM) a run stopped by a signal at the end of a step, with a frame and a checkpoint. The 2D program
// hands a 3D case to the 3D program built beside it (app/dimension_launch.hpp).
#include "app/commands.hpp"
#include "app/dimension_launch.hpp"
#include "core/files.hpp"
#include "core/version.hpp"
#include "io/case.hpp"

#include <CLI/CLI.hpp>
#include <mpi.h>
#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>

namespace {
/// MPI for the whole program; finalized on every return path.
struct MpiSession {
  MpiSession(int* argc, char*** argv) { MPI_Init(argc, argv); }
  ~MpiSession() { MPI_Finalize(); }
};

/// An option value that must not be empty (`--output ''` is refused, not read as the default).
const CLI::Validator non_empty([](std::string& s) { return s.empty() ? std::string("expected a non-empty value") : std::string(); },
                               "NON-EMPTY");

/// A finite, positive number of simulated seconds (nan, inf, 0 and negative values are refused).
const CLI::Validator positive_seconds(
    [](std::string& s) {
      char* end = nullptr;
      const double x = std::strtod(s.c_str(), &end);
      const bool ok = !s.empty() && end == s.c_str() + s.size() && std::isfinite(x) && x > 0;
      return ok ? std::string() : "'" + s + "': expected a positive, finite number of simulated seconds";
    },
    "SECONDS");

/// A whole number of steps, at least 1.
const CLI::Validator positive_steps(
    [](std::string& s) {
      const bool digits = !s.empty() && s.size() <= 12 && s.find_first_not_of("0123456789") == std::string::npos;
      return digits && std::stoull(s) > 0 ? std::string() : "'" + s + "': expected a whole number of steps, at least 1";
    },
    "N");
}  // namespace

int main(int argc, char** argv) {
  using namespace mpsfsi;
#if MPSFSI_DIM == 2
  // A 3D case goes to the 3D program, with the same arguments, before MPI starts (under mpirun every rank
  // does the same); without that program the case's check below says what to do.
  const std::string program3d = program_3d();
  if (!program3d.empty() && requested_dimension(argc, argv) == 3) {
    const std::string why = exec_program(program3d, argv);
    std::cerr << "mpsfsi: error: cannot start the 3D program " << program3d << ": " << why << "\n";
    return 1;
  }
  const std::string version = "mpsfsi " + version_and_dimension() + "\n3D program: " +
                              (program3d.empty() ? std::string("not built (CMake option MPSFSI_WITH_3D)")
                                                 : program3d + " (started for cases with dimension: 3)");
#else
  const std::string version = "mpsfsi " + version_and_dimension();
#endif
  const MpiSession mpi(&argc, &argv);
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
  CLI::App app{"mpsfsi: fluid-structure interaction with the Moving Particle Semi-implicit method"};
  app.require_subcommand(1);
  app.set_version_flag("--version", version);

  // Options shared by run and check: the case, --dp and --set.
  const auto add_case_options = [](CLI::App* cmd, RunOptions& o, const bool required) {
    cmd->add_option("case", o.case_file, required ? "Case file (YAML)" : "Case file (YAML); optional with --restart")
        ->required(required)
        ->check(CLI::ExistingFile);
    cmd->add_option("--dp", o.dp, "Particle spacing [m] (overrides dp)");
    cmd->add_option("--set", o.overrides, "Override a case value: dotted.key=value (repeatable)");
  };

  RunOptions run_opts;
  auto* run = app.add_subcommand("run", "Run a case");
  add_case_options(run, run_opts, false);
  run->add_option("--end-time", run_opts.end_time, "End time [s] (overrides time.end)");
  run->add_option("--max-steps", run_opts.max_steps, "Stop after N steps (a frame of that state is written)")
      ->check(positive_steps);
  run->add_option("--subcycles", run_opts.subcycles, "Solid sub-steps per fluid step: N or auto (overrides coupling.subcycles)")
      ->check(non_empty);
  run->add_option("--coupling", run_opts.coupling, "Coupling scheme: explicit or implicit (overrides coupling.scheme)")
      ->check(non_empty);
  run->add_option("--output", run_opts.output, "Output folder (default out/<case name>)")->check(non_empty);
  run->add_flag("--overwrite", run_opts.overwrite, "Allow writing into an existing output folder");
  run->add_flag("--quiet", run_opts.quiet, "Print only the summary and errors");
  run->add_option("--checkpoint-every", run_opts.checkpoint_every,
                  "Write checkpoint_<t>.chk into the output folder every T simulated seconds, and at the end")
      ->check(positive_seconds);
  run->add_option("--checkpoint-keep", run_opts.checkpoint_keep, "Keep only the newest N checkpoints of this run (default: all)")
      ->check(CLI::NonNegativeNumber);
  run->add_option("--restart", run_opts.restart,
                  "Continue from a checkpoint file (or a folder: its latest checkpoint); the case is the checkpoint's "
                  "unless given; output in the checkpoint's folder unless --output")
      ->check(non_empty);

  RunOptions check_opts;
  auto* check = app.add_subcommand("check", "Validate a case; print particle counts per body and the memory estimate");
  add_case_options(check, check_opts, true);
  check->add_option("--output", check_opts.output, "Also write the initial particles (.vtu/.pvd) into this folder")
      ->check(non_empty);

  // Input errors are the same on every rank: only rank 0 prints them (and the help / version text).
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  std::ostringstream no_output;
  std::ostream& out = rank == 0 ? std::cout : no_output;
  std::ostream& err = rank == 0 ? std::cerr : no_output;
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e, out, err);
  } catch (const CLI::ParseError& e) {
    app.exit(e, out, err);
    return 2;
  }

  try {
    if (*check) return command_check(check_opts);
    if (*run) return command_run(run_opts, command_line);
  } catch (const CaseError& e) {
    err << "mpsfsi: error: " << e.what() << "\n";
    return 2;
  } catch (const OutputError& e) {
    err << "mpsfsi: output error: " << e.what() << "\n";
    return 4;
  } catch (const std::exception& e) {
    std::cerr << "mpsfsi: run failed" << (rank > 0 ? " (rank " + std::to_string(rank) + ")" : "") << ": " << e.what()
              << "\n";
    return 1;
  }
  return 0;
}
