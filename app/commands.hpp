// The mpsfsi subcommands behind the command-line parser.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace mpsfsi {

struct RunOptions {
  std::string case_file;
  std::optional<double> end_time;
  std::optional<double> dp;
  std::optional<std::string> subcycles;
  std::optional<std::string> coupling;  ///< --coupling: coupling.scheme
  std::string output;
  std::vector<std::string> overrides;
  bool overwrite = false;
  bool quiet = false;
  std::string restart;              ///< run: checkpoint file (or folder: its latest checkpoint) to continue
  std::optional<double> checkpoint_every;  ///< run: simulated seconds between checkpoints
  int checkpoint_keep = 0;          ///< run: keep the newest N checkpoints (0: all)
  std::size_t max_steps = 0;        ///< run: stop after N steps (0: at the end time)

  /// The command-line shortcuts (--end-time, --dp, --subcycles, --coupling) as --set overrides, then the --set ones.
  std::vector<std::string> all_overrides() const;
};

int command_check(const RunOptions& opts);
int command_run(const RunOptions& opts, const std::string& command_line);

}  // namespace mpsfsi
