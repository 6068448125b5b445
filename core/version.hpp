// The program's version as recorded in checkpoints and printed by --version: the project version and,
// in a git checkout, the revision it was built from (generated at build time by cmake/version_info.cmake).
#pragma once

#include <string>

#ifndef MPSFSI_DIM
#define MPSFSI_DIM 2
#endif

namespace mpsfsi {

/// E.g. "0.1.0+g0123456789ab" (".dirty" appended when the build had uncommitted changes to tracked files).
const char* code_version();

/// The version and the dimension of the build, as --version and the run's first line print it:
/// "0.1.0+g0123456789ab (2D)" or "... (3D)".
inline std::string version_and_dimension() { return std::string(code_version()) + (MPSFSI_DIM == 2 ? " (2D)" : " (3D)"); }

}  // namespace mpsfsi
