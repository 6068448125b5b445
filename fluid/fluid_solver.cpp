// Semi-implicit MPS fluid step (seed 004 eq. 16-24). (Stub until the fluid issue lands.)
#include "fluid/fluid_solver.hpp"

#include <stdexcept>

namespace mpsfsi {

struct FluidSolver::Impl {};

FluidSolver::FluidSolver(const CaseSpec&, ParticleSet&, MPI_Comm) : impl_(std::make_unique<Impl>()) {}
FluidSolver::~FluidSolver() = default;
Real FluidSolver::stable_dt(std::string*) const { throw std::runtime_error("the fluid solver is not implemented yet"); }
FluidStepReport FluidSolver::advance(Real, Real) { throw std::runtime_error("the fluid solver is not implemented yet"); }

}  // namespace mpsfsi
