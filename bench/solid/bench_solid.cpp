// Benchmark of the explicit elastic solid step (seed 004 eq. 25-46, 47-48 and §4.4 contact search):
// solid particle-steps per second and bytes per particle, for square blocks of 1e4 and 1e5 particles
// (re = 2.1 dp, 12 bonds per interior particle), one core. The block is given a small random velocity
// field so that every bond is strained. Prints a Markdown table for docs/performance.md.
// Run: bench_solid [n_steps]
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <string>

using namespace mpsfsi;

int main(int argc, char** argv) {
  const int n_steps = argc > 1 ? std::max(1, std::stoi(argv[1])) : 200;
  fmt::print("| solid particles | bonds (pairs) | steps | s per step | particle-steps/s | solver bytes/particle | "
             "particle-set bytes/particle |\n");
  fmt::print("|---|---|---|---|---|---|---|\n");
  for (const int side : {100, 316}) {
    CaseSpec spec;
    spec.file = "bench";
    spec.dp = 0.01;
    SolidMaterial m;
    m.name = "m";
    m.rho = 1000;
    m.E = 1e7;
    m.nu = 0.3;
    m.fracture_strain = 0.5;  // fracture check on, nothing breaks
    spec.solid_materials.push_back(m);
    BodySpec b;
    b.name = "block";
    b.kind = BodyKind::solid;
    b.material = "m";
    b.rect = {Vec(0, 0), Vec(side * spec.dp, side * spec.dp)};
    spec.bodies.push_back(b);
    spec.gravity = Vec(0, -9.81);
    Scene scene = build_scene(spec);
    auto& p = scene.particles;
    std::mt19937 rng(1);
    std::uniform_real_distribution<Real> u(-0.01, 0.01);
    for (auto& v : p.velocity) v = Vec(u(rng), u(rng));
    SolidSolver solid(solid_setup(spec), p);
    const Real dt = solid.stable_dt();
    for (int k = 0; k < 5; ++k) solid.advance(k * dt, dt);  // warm-up
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < n_steps; ++k) solid.advance(k * dt, dt);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double n = static_cast<double>(p.size());
    fmt::print("| {} | {} | {} | {:.3e} | {:.2e} | {:.0f} | {:.0f} |\n", p.size(), solid.n_bonds(), n_steps, s / n_steps,
               n * n_steps / s, static_cast<double>(solid.memory_bytes()) / n, static_cast<double>(p.memory_bytes()) / n);
  }
  return 0;
}
