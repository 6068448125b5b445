// One program for 2D and 3D cases. The dimension is a compile-time constant of a build; the 2D build also
// builds the 3D program (<build>/3d/mpsfsi, CMakeLists.txt MPSFSI_WITH_3D). `mpsfsi run|check` of the 2D
// program looks at the case's `dimension:` (or the checkpoint's case with --restart, and a `--set
// dimension=N`) before anything else and, for a 3D case, replaces itself by the 3D program with the same
// arguments (under mpirun each rank does, before MPI starts).
#pragma once

#include <string>

namespace mpsfsi {

/// The dimension of the case that this command line runs or checks: the case file's `dimension:` (default
/// 2), the checkpoint's case with --restart and no case file, a `--set dimension=N` over either. 0 when
/// there is no case or it cannot be read: the program's own parsing then says what is wrong.
int requested_dimension(int argc, char** argv);

/// The 3D program next to this one (<folder of this program>/3d/mpsfsi), or "" when it was not built.
std::string program_3d();

/// Replaces this process by `program` with this process's arguments; returns only if that failed, with
/// the reason.
std::string exec_program(const std::string& program, char** argv);

}  // namespace mpsfsi
