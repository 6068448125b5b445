// Explicit rotation-aware elastic MPS (seed 004 eq. 25-48). (Stub until the solid issue lands.)
#include "solid/solid_solver.hpp"

#include <stdexcept>

namespace mpsfsi {

struct SolidSolver::Impl {};

SolidSolver::SolidSolver(const CaseSpec&, ParticleSet&) : impl_(std::make_unique<Impl>()) {}
SolidSolver::~SolidSolver() = default;
Real SolidSolver::stable_dt() const { throw std::runtime_error("the solid solver is not implemented yet"); }
SolidStepReport SolidSolver::advance(Real, Real) { throw std::runtime_error("the solid solver is not implemented yet"); }
void SolidSolver::prepare_output(Real) {}

}  // namespace mpsfsi
