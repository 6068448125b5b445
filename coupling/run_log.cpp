// The run's progress line, notes and run.jsonl (coupling/run_log.hpp).
#include "coupling/run_log.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <stdexcept>
#include <unistd.h>

namespace mpsfsi {

RunLog::RunLog(const std::string& dir, const bool append, const bool quiet, const int rank) {
  print_ = rank == 0 && !quiet;
  tty_ = print_ && isatty(fileno(stdout));
  if (rank != 0) return;
  path_ = dir + "/run.jsonl";
  jsonl_.open(path_, append ? std::ios::app : std::ios::trunc);
  if (!jsonl_) throw std::runtime_error("cannot write " + path_);
}

void RunLog::print(const std::string& text) {
  if (!print_) return;
  fmt::print("{}\n", text);
  std::fflush(stdout);
}

void RunLog::note(const std::string& text) {
  if (!print_) return;
  fmt::print("{}{}\n", tty_ ? "\n" : "", text);
  std::fflush(stdout);
}

void RunLog::end_line() {
  if (tty_) fmt::print("\n");
}

void RunLog::event(const std::string& json) {
  if (!jsonl_.is_open()) return;
  jsonl_ << json << '\n';
  jsonl_.flush();  // `tail -f run.jsonl` follows the run; may fail on a full disk
  if (!jsonl_ && error_.empty()) error_ = "cannot write run log '" + path_ + "'";
}

void RunLog::progress(const std::string& line, const std::string& json, const bool due, const bool final) {
  if (due) event(json);
  if (!print_) return;
  if (tty_) {
    if (final || seconds_since(last_tty_) > 0.2) {
      fmt::print("\r{:<120}", line);
      if (final) fmt::print("\n");
      std::fflush(stdout);
      last_tty_ = Clock::now();
    }
  } else if (due) {
    fmt::print("{}\n", line);
    std::fflush(stdout);  // a redirected log gets each line as it is printed
  }
}

std::string RunLog::json_escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

}  // namespace mpsfsi
