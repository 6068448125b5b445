// One program for 2D and 3D cases (app/dimension_launch.hpp).
#include "app/dimension_launch.hpp"

#include "coupling/checkpoint.hpp"
#include "io/case.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

namespace mpsfsi {

namespace {

/// The options of `run` and `check` that take a value (the case file is the first other argument).
bool takes_value(const std::string& option) {
  static const char* names[] = {"--dp", "--set", "--end-time", "--max-steps", "--subcycles", "--coupling",
                                "--output", "--checkpoint-every", "--checkpoint-keep", "--restart"};
  for (const char* n : names)
    if (option == n) return true;
  return false;
}

}  // namespace

int requested_dimension(const int argc, char** argv) {
  if (argc < 2) return 0;
  const std::string command = argv[1];
  if (command != "run" && command != "check") return 0;
  std::string case_file, restart, set_dimension;
  for (int i = 2; i < argc; ++i) {
    std::string arg = argv[i], value;
    const auto eq = arg.find('=');
    const bool inline_value = arg.rfind("--", 0) == 0 && eq != std::string::npos;
    if (inline_value) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
    }
    if (arg.rfind("--", 0) != 0) {
      if (case_file.empty()) case_file = arg;
      continue;
    }
    if (!takes_value(arg)) continue;
    if (!inline_value) {
      if (i + 1 >= argc) break;
      value = argv[++i];
    }
    if (arg == "--restart") restart = value;
    if (arg == "--set" && value.rfind("dimension=", 0) == 0) set_dimension = value.substr(10);
  }
  int d = 0;
  if (!case_file.empty()) {
    d = peek_case_dimension(case_file, true);
  } else if (!restart.empty()) {
    const std::string text = peek_checkpoint_case(restart);
    if (text.empty()) return 0;
    d = peek_case_dimension(text, false);
  } else {
    return 0;
  }
  if (!set_dimension.empty()) d = set_dimension == "2" ? 2 : set_dimension == "3" ? 3 : 0;
  return d;
}

std::string program_3d() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const std::filesystem::path p = self.parent_path() / "3d" / "mpsfsi";
  return std::filesystem::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0 ? p.string() : std::string();
}

std::string exec_program(const std::string& program, char** argv) {
  std::vector<char*> args;
  args.push_back(const_cast<char*>(program.c_str()));
  for (char** a = argv + 1; *a != nullptr; ++a) args.push_back(*a);
  args.push_back(nullptr);
  execv(program.c_str(), args.data());
  return std::strerror(errno);
}

}  // namespace mpsfsi
