// Partitioned fluid-solid coupling (seed 004 §4.5, eq. 49-51): see fsi_interface.hpp.
#include "coupling/fsi_interface.hpp"

#include "core/binary_io.hpp"
#include "core/files.hpp"
#include "core/kernel.hpp"
#include "core/operators.hpp"
#include "solid/solid_solver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mpsfsi {

SubcycleChoice choose_subcycles(const int requested, const Real dt_fluid, const Real dt_solid) {
  SubcycleChoice c;
  const int automatic = std::max(1, static_cast<int>(std::ceil(dt_fluid / dt_solid * (1 - 1e-12))));
  if (requested <= 0) {
    c.n = automatic;
  } else if (requested < automatic) {
    c.n = automatic;
    c.raised = true;
  } else {
    c.n = requested;
  }
  return c;
}

FsiInterface::FsiInterface(const CaseSpec& spec, ParticleSet& particles, const FsiOptions& options)
    : p_(particles), opt_(options) {
  dp_ = spec.dp;
  re_ = spec.fluid.re_gradient * spec.dp;
  n0_ = lattice_constants(dp_, re_).n0;
}

FluidOptions FsiInterface::fluid_options(const FsiOptions& options, FluidOptions base) {
  base.solid_as_boundary = false;
  base.boundary_flag_field = options.flag_field;
  if (options.freeze_solid_density) base.density_offset_field = options.offset_field;
  return base;
}

void FsiInterface::initialize() {
  // (n_i^0)_solid: number density of each solid particle counting solid particles only (eq. 51).
  std::vector<Vec> xs;
  std::vector<GlobalId> ids;
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (p_.kind[i] == ParticleKind::solid) {
      xs.push_back(p_.position[i]);
      ids.push_back(p_.global_id[i]);
    }
  NeighbourList nl;
  build_neighbour_list(xs, re_, nl);
  n0_solid_.clear();
  n0_solid_.reserve(xs.size());
  for (std::size_t k = 0; k < xs.size(); ++k) {
    n0_solid_[ids[k]] = number_density_at(xs, nl, re_, k).n;
  }
  bodies_.clear();
  body_slot_.assign(p_.bodies.size(), -1);
  for (std::size_t b = 0; b < p_.bodies.size(); ++b)
    if (p_.bodies[b].kind == ParticleKind::solid) {
      body_slot_[b] = static_cast<int>(bodies_.size());
      InterfaceBody ib;
      ib.name = p_.bodies[b].name;
      ib.body = static_cast<std::uint16_t>(b);
      bodies_.push_back(ib);
    }
  p_.add_vector_field(opt_.load_field);
  if (opt_.freeze_solid_density) p_.add_scalar_field(opt_.offset_field);
  initialized_ = true;
}

void FsiInterface::prepare_fluid_boundary(const Real dt) {
  if (!initialized_) throw std::logic_error("FsiInterface: call initialize() first");
  if (!p_.has_scalar_field(opt_.flag_field))
    throw std::logic_error("FsiInterface: the solid does not publish its surface flag '" + opt_.flag_field + "'");
  saved_.clear();
  if (opt_.midstep_predictor && dt > 0 && !mean_v_.empty()) {
    for (std::size_t i = 0; i < p_.size(); ++i) {
      if (p_.kind[i] != ParticleKind::solid) continue;
      saved_.push_back({p_.global_id[i], p_.position[i], p_.velocity[i]});
      const auto it = mean_v_.find(p_.global_id[i]);
      const Vec u = it != mean_v_.end() ? it->second : Vec::Zero();
      p_.position[i] += 0.5 * dt * u;
      p_.velocity[i] = u;
    }
  }
  if (!opt_.freeze_solid_density) return;
  solid_x_.clear();
  solid_i_.clear();
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (p_.kind[i] == ParticleKind::solid) {
      solid_x_.push_back(p_.position[i]);
      solid_i_.push_back(static_cast<LocalIndex>(i));
    }
  build_neighbour_list(solid_x_, re_, solid_nl_, solid_grid_);
  auto& offset = p_.scalar_field(opt_.offset_field);
  for (std::size_t k = 0; k < solid_x_.size(); ++k) {
    const auto i = static_cast<std::size_t>(solid_i_[k]);
    offset[i] = n0_solid_.at(p_.global_id[i]) - number_density_at(solid_x_, solid_nl_, re_, k).n;
  }
}

void FsiInterface::restore_solid() {
  if (saved_.empty()) return;
  std::size_t k = 0;
  for (std::size_t i = 0; i < p_.size() && k < saved_.size(); ++i) {
    if (p_.kind[i] != ParticleKind::solid) continue;
    // Removal keeps the order of the remaining particles, and solids are never removed.
    if (p_.global_id[i] != saved_[k].id) throw std::logic_error("FsiInterface: the solid particles changed order");
    p_.position[i] = saved_[k].x;
    p_.velocity[i] = saved_[k].v;
    ++k;
  }
  saved_.clear();
}

void FsiInterface::compute_load() {
  if (!initialized_) throw std::logic_error("FsiInterface: call initialize() first");
  auto& load = p_.vector_field(opt_.load_field);
  const auto& flag = p_.scalar_field(opt_.flag_field);
  const auto& pressure = p_.scalar_field(opt_.pressure_field);
  std::fill(load.begin(), load.end(), Vec::Zero());
  loaded_.clear();
  for (auto& b : bodies_) {
    b.force.setZero();
    b.n_wetted = 0;
  }
  // The loaded particles (solid surface, eq. 48) and their neighbours among all particles.
  rows_.clear();
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (p_.kind[i] == ParticleKind::solid && flag[i] != 0 && !(opt_.exclude_clamped && p_.clamped[i]))
      rows_.push_back(static_cast<LocalIndex>(i));
  build_neighbour_list_of(p_.position, rows_, re_, rows_nl_, grid_);
  const Real volume = std::pow(dp_, dim);
  for (std::size_t q = 0; q < rows_.size(); ++q) {
    const auto i = static_cast<std::size_t>(rows_[q]);
    const auto it = n0_solid_.find(p_.global_id[i]);
    if (it == n0_solid_.end()) throw std::logic_error("FsiInterface: a solid particle appeared after initialize()");
    const Real pi = pressure[i];
    Real n_total = 0;
    Vec sum = Vec::Zero();
    bool wet = false;
    for_each_pair_in_row(p_.position, rows_nl_, re_, q, i, AllNeighbours{},
                         [&](const std::size_t j, const Vec& rij, const Real r2, const Real w) {
                           n_total += w;  // eq. 8 over every neighbour
                           const bool fluid = p_.kind[j] == ParticleKind::fluid;
                           if (!fluid && !(p_.kind[j] == ParticleKind::solid && flag[j] != 0 &&
                                           !(opt_.exclude_clamped && p_.clamped[j])))
                             return;  // j*: fluid, solid surface (not clamped)
                           wet = wet || fluid;
                           sum += (0.5 * (pi + pressure[j]) * w / r2) * rij;
                         });
    const Real n_tilde = n_total - it->second;  // eq. 51
    if (!wet || !(n_tilde > 0)) continue;
    const Real n_norm = opt_.normalisation == FsiOptions::Normalisation::seed ? n_tilde : n0_;
    Vec f = -volume * (2.0 * dim / n_norm) * sum;  // eq. 50 times the particle volume, as -grad P
    if (opt_.load_relaxation < 1) {
      const auto prev = prev_load_.find(p_.global_id[i]);
      if (prev != prev_load_.end()) f = opt_.load_relaxation * f + (1 - opt_.load_relaxation) * prev->second;
    }
    load[i] = f;
    loaded_.push_back(static_cast<LocalIndex>(i));
    const int slot = body_slot_[p_.body[i]];
    if (slot >= 0) {
      bodies_[static_cast<std::size_t>(slot)].force += f;
      ++bodies_[static_cast<std::size_t>(slot)].n_wetted;
    }
  }
  if (opt_.load_relaxation < 1) {  // a particle that falls dry starts afresh
    prev_load_.clear();
    for (const LocalIndex li : loaded_) prev_load_[p_.global_id[static_cast<std::size_t>(li)]] = load[static_cast<std::size_t>(li)];
  }
}

void FsiInterface::advance_solid(SolidSolver& solid, const Real t, const Real dt, const int n_sub) {
  if (n_sub < 1) throw std::invalid_argument(fmt::format("FsiInterface::advance_solid: n_sub = {} < 1", n_sub));
  const Real dts = dt / n_sub;
  for (auto& b : bodies_) b.work_step = 0;
  const auto& load = p_.vector_field(opt_.load_field);
  solid_x_.clear();
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (p_.kind[i] == ParticleKind::solid) solid_x_.push_back(p_.position[i]);
  for (int k = 0; k < n_sub; ++k) {
    solid.advance(t + k * dts, dts);
    // Symplectic Euler: the displacement of the sub-step is v_new dts, so F . v_new dts is the work.
    for (const LocalIndex li : loaded_) {
      const auto i = static_cast<std::size_t>(li);
      const int slot = body_slot_[p_.body[i]];
      if (slot >= 0) bodies_[static_cast<std::size_t>(slot)].work_step += dts * load[i].dot(p_.velocity[i]);
    }
  }
  for (auto& b : bodies_) b.work_total += b.work_step;
  std::size_t k = 0;
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (p_.kind[i] == ParticleKind::solid) mean_v_[p_.global_id[i]] = (p_.position[i] - solid_x_[k++]) / dt;
}

void FsiInterface::open_csv(const std::string& path, const bool append) {
  csv_.open(path, append ? std::ios::app : std::ios::trunc);
  csv_path_ = path;
  check_written(csv_, csv_path_, "interface table");
  if (!append) csv_ << "time,body,fx,fy,work_step,work_total,wetted\n";
}

namespace {
/// A GlobalId -> Vec map as two arrays sorted by id (the file does not depend on the hash order).
void save_map(BinaryWriter& out, const std::unordered_map<GlobalId, Vec>& m) {
  std::vector<std::pair<GlobalId, Vec>> items(m.begin(), m.end());
  std::sort(items.begin(), items.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<GlobalId> ids;
  std::vector<Vec> values;
  for (const auto& [id, v] : items) {
    ids.push_back(id);
    values.push_back(v);
  }
  out.array(ids);
  out.array(values);
}

std::unordered_map<GlobalId, Vec> load_map(BinaryReader& in, const char* what) {
  const auto ids = in.array<GlobalId>(what);
  const auto values = in.array<Vec>(what, ids.size());
  std::unordered_map<GlobalId, Vec> m;
  m.reserve(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) m.emplace(ids[k], values[k]);
  return m;
}
}  // namespace

void FsiInterface::save_state(BinaryWriter& out) const {
  out.section("coupling");
  out.u64(bodies_.size());
  for (const auto& b : bodies_) {
    out.string(b.name);
    out.value(b.force);
    out.f64(b.work_step);
    out.f64(b.work_total);
    out.u64(b.n_wetted);
  }
  save_map(out, prev_load_);
  save_map(out, mean_v_);
}

void FsiInterface::load_state(BinaryReader& in) {
  in.expect_section("coupling");
  const std::size_t nb = in.u64("the interface body count");
  if (nb != bodies_.size())
    in.fail(fmt::format("the checkpoint's interface has {} solid bodies, this case {}", nb, bodies_.size()));
  std::vector<InterfaceBody> bodies = bodies_;
  for (auto& b : bodies) {
    const std::string name = in.string("an interface body name");
    if (name != b.name) in.fail("the checkpoint's interface body '" + name + "' is '" + b.name + "' in this case");
    b.force = in.value<Vec>("an interface force");
    b.work_step = in.f64("an interface work");
    b.work_total = in.f64("an interface work");
    b.n_wetted = in.u64("a wetted count");
  }
  auto prev = load_map(in, "the previous interface load");
  auto mean_v = load_map(in, "the solid's mean velocity");
  bodies_.swap(bodies);
  prev_load_.swap(prev);
  mean_v_.swap(mean_v);
}

void FsiInterface::write_csv(const Real t) {
  if (!csv_.is_open()) return;
  for (const auto& b : bodies_)
    csv_ << fmt::format("{:.9g},{},{:.9g},{:.9g},{:.9g},{:.9g},{}\n", t, b.name, b.force[0], b.force[1], b.work_step,
                        b.work_total, b.n_wetted);
  csv_.flush();
  check_written(csv_, csv_path_, "interface table");
}

}  // namespace mpsfsi
