// What a run tells its user and its log, on rank 0: the progress (one updating line on a terminal, a plain
// line every log_every steps otherwise), notes and warnings, and run.jsonl, one JSON object per event (step,
// projection, distribution, checkpoint, restart, failure, interrupted, summary; docs/user-guide.md). The run loop
// (coupling/simulation.cpp) decides what to say and when; this part says it.
#pragma once

#include "core/stopwatch.hpp"

#include <fstream>
#include <string>

namespace mpsfsi {

class RunLog {
 public:
  /// On rank 0 opens dir/run.jsonl (appended to when `append`); throws std::runtime_error when it cannot.
  /// Prints nothing on other ranks or when `quiet`.
  RunLog(const std::string& dir, bool append, bool quiet, int rank);

  /// Whether this rank prints (rank 0, not quiet).
  bool printing() const { return print_; }
  /// Whether the progress line is the terminal's updating line.
  bool terminal() const { return tty_; }

  /// Prints a line as it is (rank 0, not quiet).
  void print(const std::string& text);
  /// Prints a note on its own line: on a terminal below the progress line (rank 0, not quiet).
  void note(const std::string& text);
  /// Ends the terminal's progress line (before a message on stderr).
  void end_line();
  /// Appends one JSON object to run.jsonl and flushes it (rank 0; a no-op elsewhere or after a failed open).
  void event(const std::string& json);
  /// The progress line: on a terminal redrawn at most every 0.2 s (and when `final`), otherwise printed when
  /// `due`; with `due`, `json` also goes to run.jsonl.
  void progress(const std::string& line, const std::string& json, bool due, bool final);
  /// Not empty once run.jsonl could not be written: the message the run stops with at its next output.
  const std::string& error() const { return error_; }

  /// s with quotes, backslashes and line breaks escaped for a JSON string.
  static std::string json_escape(const std::string& s);

 private:
  std::string path_;
  std::ofstream jsonl_;
  bool print_ = false, tty_ = false;
  Clock::time_point last_tty_{};
  std::string error_;
};

}  // namespace mpsfsi
