// Micro-benchmark of the pressure solve's kernels on one real PPE matrix (cases/dam_break.yaml at
// l0 = 1.6 mm after N steps, one rank): Tpetra CrsMatrix::apply against a hand-written CRS loop, the
// Tpetra vector operations of one CG iteration (dot, norm, update), and Belos CG (PseudoBlock / Block)
// against a hand-written CG on the same Tpetra objects, all run for a fixed number of iterations, to
// split the cost of one CG iteration into SpMV, vector operations and Belos overhead.
// Usage: bench_fluid_spmv [n_steps [dp]]. Results go to docs/performance.md (## Fluid, ### Pressure solve).
#include "core/distribution.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <BelosLinearProblem.hpp>
#include <BelosSolverFactory.hpp>
#include <BelosTpetraAdapter.hpp>
#include <Kokkos_Core.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_MultiVector.hpp>

#include <fmt/format.h>
#include <mpi.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

using namespace mpsfsi;

namespace {

using Map = Tpetra::Map<>;
using Matrix = Tpetra::CrsMatrix<double>;
using MV = Tpetra::MultiVector<double>;
using OP = Tpetra::Operator<double>;
using LO = Map::local_ordinal_type;
using Teuchos::RCP;
using Teuchos::rcp;

double time_ms(const int reps, const std::function<void()>& f) {
  f();  // warm-up
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < reps; ++k) f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / reps;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  Kokkos::initialize();
  {
    const int n_steps = argc > 1 ? std::stoi(argv[1]) : 20;
    const std::string dp = argc > 2 ? argv[2] : "0.0016";
    const CaseSpec spec = load_case(std::string(MPSFSI_SOURCE_DIR) + "/cases/dam_break.yaml",
                                    {"dp=" + dp, "fluid.preconditioner=jacobi"});
    Scene scene = build_scene(spec);
    Distribution self(MPI_COMM_SELF, {});
    FluidSolver fluid(fluid_setup(spec), scene.particles, self);
    Real t = 0;
    for (int s = 0; s < n_steps; ++s) {
      const Real dt = fluid.stable_dt();
      fluid.advance(t, dt);
      t += dt;
    }
    const LocalRows& sys = fluid.last_system();
    const std::size_t n = sys.n_rows(), nnz = sys.col.size();

    auto comm = rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
    auto map = rcp(new Map(static_cast<Tpetra::global_size_t>(n), 0, comm));
    using RowPtr = Matrix::local_graph_device_type::row_map_type::non_const_type;
    using Entries = Matrix::local_graph_device_type::entries_type::non_const_type;
    using Values = Matrix::local_matrix_device_type::values_type;
    RowPtr ptr("ptr", n + 1);
    Entries ind("ind", nnz);
    Values val("val", nnz);
    for (std::size_t k = 0; k <= n; ++k) ptr(k) = sys.row_ptr[k];
    for (std::size_t k = 0; k < nnz; ++k) {
      ind(k) = static_cast<LO>(sys.col[k]);
      val(k) = sys.value[k];
    }
    auto A = rcp(new Matrix(map, map, ptr, ind, val));
    A->expertStaticFillComplete(map, map);
    MV x(map, 1), y(map, 1), z(map, 1);
    x.randomize();
    y.randomize();
    fmt::print("PPE after {} steps: {} rows, {} nnz ({:.1f} per row), matrix {:.1f} MB\n", n_steps, n, nnz,
               static_cast<double>(nnz) / static_cast<double>(n), static_cast<double>(nnz) * 12e-6);

    const int reps = 200;
    fmt::print("| kernel | ms |\n|---|---|\n");
    fmt::print("| Tpetra CrsMatrix::apply | {:.3f} |\n", time_ms(reps, [&] { A->apply(x, y); }));
    {
      std::vector<int> rp(sys.row_ptr.begin(), sys.row_ptr.end()), ci(nnz);
      for (std::size_t k = 0; k < nnz; ++k) ci[k] = static_cast<int>(sys.col[k]);
      std::vector<double> xv(n, 1.0), yv(n);
      const double* v = sys.value.data();
      fmt::print("| hand-written CRS loop (int cols, double values) | {:.3f} |\n", time_ms(reps, [&] {
                   for (std::size_t r = 0; r < n; ++r) {
                     double s = 0;
                     for (int k = rp[r]; k < rp[r + 1]; ++k) s += v[k] * xv[static_cast<std::size_t>(ci[k])];
                     yv[r] = s;
                   }
                 }));
      std::vector<float> vf(sys.value.begin(), sys.value.end());
      fmt::print("| hand-written CRS loop (int cols, float values) | {:.3f} |\n", time_ms(reps, [&] {
                   for (std::size_t r = 0; r < n; ++r) {
                     double s = 0;
                     for (int k = rp[r]; k < rp[r + 1]; ++k) s += vf[static_cast<std::size_t>(k)] * xv[static_cast<std::size_t>(ci[k])];
                     yv[r] = s;
                   }
                 }));
    }
    Teuchos::Array<double> d(1);
    fmt::print("| Tpetra dot | {:.4f} |\n", time_ms(reps * 10, [&] { x.dot(y, d()); }));
    fmt::print("| Tpetra norm2 | {:.4f} |\n", time_ms(reps * 10, [&] { x.norm2(d()); }));
    fmt::print("| Tpetra update (axpy) | {:.4f} |\n", time_ms(reps * 10, [&] { y.update(1e-3, x, 1.0); }));
    fmt::print("| Tpetra elementWiseMultiply (Jacobi apply) | {:.4f} |\n",
               time_ms(reps * 10, [&] { z.elementWiseMultiply(1.0, *x.getVector(0), y, 0.0); }));

    // Fixed-iteration CG: Belos solvers and a hand-written loop on the same Tpetra objects.
    const int iters = 100;
    auto b = rcp(new MV(map, 1));
    b->randomize();
    for (const char* name : {"PSEUDOBLOCK CG", "BLOCK CG", "PSEUDOBLOCK STOCHASTIC CG"}) {
      auto params = rcp(new Teuchos::ParameterList);
      params->set("Convergence Tolerance", 1e-300);
      params->set("Maximum Iterations", iters);
      params->set("Verbosity", 0);
      Belos::SolverFactory<double, MV, OP> factory;
      RCP<Belos::SolverManager<double, MV, OP>> belos;
      try {
        belos = factory.create(name, params);
      } catch (const std::exception& e) {
        fmt::print("| Belos {}: not available ({}) | |\n", name, e.what());
        continue;
      }
      auto X = rcp(new MV(map, 1));
      double ms = 0;
      int it = 0;
      for (int rep = 0; rep < 3; ++rep) {
        X->putScalar(0.0);
        auto problem = rcp(new Belos::LinearProblem<double, MV, OP>(A, X, b));
        problem->setProblem();
        belos->setProblem(problem);
        const auto t0 = std::chrono::steady_clock::now();
        belos->solve();
        ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        it = belos->getNumIters();
      }
      fmt::print("| Belos {} per iteration ({} it) | {:.3f} |\n", name, it, ms / it);
    }
    {
      MV X(map, 1), R(map, 1), P(map, 1), Q(map, 1);
      Teuchos::Array<double> rr(1), pq(1);
      const double ms = time_ms(3, [&] {
        X.putScalar(0.0);
        R.assign(*b);
        P.assign(R);
        R.dot(R, rr());
        for (int k = 0; k < iters; ++k) {
          A->apply(P, Q);
          P.dot(Q, pq());
          const double alpha = rr[0] / pq[0];
          X.update(alpha, P, 1.0);
          R.update(-alpha, Q, 1.0);
          const double old = rr[0];
          R.dot(R, rr());
          P.update(1.0, R, rr[0] / old);
        }
      });
      fmt::print("| hand-written CG on Tpetra per iteration | {:.3f} |\n", ms / iters);
    }
  }
  Kokkos::finalize();
  MPI_Finalize();
  return 0;
}
