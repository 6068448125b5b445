// The error of a physics solver's setup that does not fit the particles it was given (e.g. a solid load
// whose region holds no particle of its body, a source with too few particles in range): input that only
// the built scene can refute. A std::invalid_argument; the run loop (coupling/simulation.cpp) reports it
// as a case error (exit 2), since io/ checks every other input before the solvers see it.
#pragma once

#include <stdexcept>

namespace mpsfsi {

class SetupError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

}  // namespace mpsfsi
