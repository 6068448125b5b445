// Partitioned fluid-solid coupling (seed 004 §4.5, eq. 49-51): see fsi_interface.hpp.
#include "coupling/fsi_interface.hpp"

#include "core/binary_io.hpp"
#include "core/collectives.hpp"
#include "core/distribution.hpp"
#include "core/files.hpp"
#include "core/kernel.hpp"
#include "core/operators.hpp"
#include "solid/solid_solver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

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

namespace {
/// The interface's internal per-particle fields (not written unless asked for; they travel between ranks and
/// into checkpoints with their particle).
namespace field {
constexpr const char* n0_solid = "_fsi_n0_solid";      ///< (n_i^0)_solid of eq. 51
constexpr const char* prev_load = "_fsi_prev_load";    ///< the load applied in the previous step
constexpr const char* had_load = "_fsi_had_load";      ///< 1: prev_load holds a load (the particle was wetted)
constexpr const char* mean_v = "_fsi_mean_v";          ///< the solid's mean velocity over the last step
constexpr const char* start_x = "_fsi_start_x";        ///< the solid's position at the start of advance_solid
constexpr const char* load = "_fsi_load";              ///< the interface force of the last compute_load
}  // namespace field
}  // namespace

FsiInterface::FsiInterface(const CaseSpec& spec, ParticleSet& particles, const FsiOptions& options,
                           Distribution* distribution)
    : p_(particles), opt_(options), dist_(distribution) {
  dp_ = spec.dp;
  re_ = spec.fluid.re_gradient * spec.dp;
  n0_ = lattice_constants(dp_, re_).n0;
}

FluidOptions FsiInterface::fluid_options(FluidOptions base) {
  base.solid_as_boundary = false;
  base.coupled_solid = true;  // the coupling gives the fluid its view of the solid (prepare_fluid_boundary)
  return base;
}

void FsiInterface::sync() {
  if (dist_) dist_->renew(p_, {"position", "velocity"}, ParticleKind::solid);  // only the solid moved
}

void FsiInterface::reduce_bodies(const bool force) {
  if (!dist_ || dist_->n_ranks() == 1 || bodies_.empty()) return;
  std::vector<double> v;
  for (const auto& b : bodies_) {
    if (force) {
      for (int a = 0; a < dim; ++a) v.push_back(b.force[a]);
      v.push_back(static_cast<double>(b.n_wetted));
    } else {
      v.push_back(b.work_step);
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), MPI_DOUBLE, MPI_SUM, dist_->comm());
  std::size_t q = 0;
  for (auto& b : bodies_) {
    if (force) {
      for (int a = 0; a < dim; ++a) b.force[a] = v[q++];
      b.n_wetted = static_cast<std::size_t>(v[q++]);
    } else {
      b.work_step = v[q++];
    }
  }
}

void FsiInterface::initialize() {
  for (const char* name : {field::n0_solid, field::had_load}) p_.add_scalar_field(name);
  for (const char* name : {field::load, field::prev_load, field::mean_v, field::start_x})
    p_.add_vector_field(name);
  sync();
  // (n_i^0)_solid: number density of each solid particle counting solid particles only (eq. 51), over this
  // rank's particles and ghosts.
  std::vector<Vec> xs;
  std::vector<LocalIndex> at;
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (p_.kind[i] == ParticleKind::solid) {
      xs.push_back(p_.position[i]);
      at.push_back(static_cast<LocalIndex>(i));
    }
  NeighbourList nl;
  build_neighbour_list(xs, re_, nl);
  auto& n0_solid = p_.scalar_field(field::n0_solid);
  for (std::size_t k = 0; k < xs.size(); ++k) n0_solid[static_cast<std::size_t>(at[k])] = number_density_at(xs, nl, re_, k).n;
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
  initialized_ = true;
}

SolidBoundaryData FsiInterface::prepare_fluid_boundary(const Real dt) {
  if (!(opt_.midstep_predictor && dt > 0 && has_mean_v_)) return view_solid(nullptr);
  const auto& mean_v = p_.vector_field(field::mean_v);
  const SolidView at_mid_step = [&](std::size_t, const std::size_t i) {
    return std::pair<Vec, Vec>(0.5 * dt * mean_v[i], mean_v[i]);
  };
  return view_solid(&at_mid_step);
}

SolidBoundaryData FsiInterface::prepare_fluid_boundary(const Real dt, const Eigen::VectorXd& displacement) {
  if (!(dt > 0)) throw std::invalid_argument("FsiInterface::prepare_fluid_boundary: dt must be positive");
  std::size_t n_solid = 0;
  for (std::size_t i = 0; i < p_.n_owned(); ++i) n_solid += p_.kind[i] == ParticleKind::solid ? 1 : 0;
  if (static_cast<std::size_t>(displacement.size()) != dim * n_solid)
    throw std::logic_error(fmt::format("FsiInterface::prepare_fluid_boundary: {} displacement values for {} owned solid "
                                       "particles", displacement.size(), n_solid));
  const SolidView at_mid_step = [&](const std::size_t k, std::size_t) {
    const Vec d = displacement.segment<dim>(static_cast<Eigen::Index>(dim * k));
    return std::pair<Vec, Vec>(d, d / dt);
  };
  return view_solid(&at_mid_step);
}

std::vector<GlobalId> FsiInterface::solid_ids() const { return owned_ids(p_, ParticleKind::solid); }

Eigen::VectorXd FsiInterface::predicted_displacement(const Real dt) const {
  const std::vector<GlobalId> ids = solid_ids();
  Eigen::VectorXd d = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(dim * ids.size()));
  if (!has_mean_v_) return d;
  const auto& mean_v = p_.vector_field(field::mean_v);
  Eigen::Index k = 0;
  for (std::size_t i = 0; i < p_.n_owned(); ++i)
    if (p_.kind[i] == ParticleKind::solid) d.segment<dim>(dim * k++) = dt * mean_v[i];
  return d;
}

Eigen::VectorXd FsiInterface::step_displacement(const std::vector<GlobalId>& ids) const {
  const auto& start_x = p_.vector_field(field::start_x);
  std::unordered_map<GlobalId, Vec> mine;
  for (std::size_t i = 0; i < p_.n_owned(); ++i)
    if (p_.kind[i] == ParticleKind::solid) mine.emplace(p_.global_id[i], p_.position[i] - start_x[i]);
  int missing = 0;
  for (const GlobalId id : ids) missing = missing || !mine.count(id);
  if (dist_ && dist_->n_ranks() > 1) {
    MPI_Allreduce(MPI_IN_PLACE, &missing, 1, MPI_INT, MPI_MAX, dist_->comm());
    if (missing) {  // some solid particle changed its rank within the step: every rank's (id, d) to every rank
      std::vector<double> flat;
      for (const auto& [id, d] : mine) {
        flat.push_back(static_cast<double>(id));
        for (int a = 0; a < dim; ++a) flat.push_back(d[a]);
      }
      const std::vector<double> all = all_gather(dist_->comm(), flat);
      for (std::size_t q = 0; q + dim < all.size(); q += dim + 1) {
        Vec d;
        for (int a = 0; a < dim; ++a) d[a] = all[q + 1 + static_cast<std::size_t>(a)];
        mine.emplace(static_cast<GlobalId>(all[q]), d);
      }
    }
  }
  Eigen::VectorXd out(static_cast<Eigen::Index>(dim * ids.size()));
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const auto it = mine.find(ids[k]);
    if (it == mine.end()) throw std::logic_error(fmt::format("FsiInterface::step_displacement: solid particle {} not found", ids[k]));
    out.segment<dim>(static_cast<Eigen::Index>(dim * k)) = it->second;
  }
  return out;
}

SolidBoundaryData FsiInterface::view_solid(const SolidView* view) {
  if (!initialized_) throw std::logic_error("FsiInterface: call initialize() first");
  if (!p_.has_scalar_field(opt_.flag_field))
    throw std::logic_error("FsiInterface: the solid does not publish its surface flag '" + opt_.flag_field + "'");
  SolidBoundaryData data;
  data.density_offsets = opt_.freeze_solid_density;
  const auto& flag = p_.scalar_field(opt_.flag_field);
  const auto& n0_solid = p_.scalar_field(field::n0_solid);
  std::size_t k = 0;
  for (std::size_t i = 0; i < p_.n_owned(); ++i) {
    if (p_.kind[i] != ParticleKind::solid) continue;
    data.ids.push_back(p_.global_id[i]);
    data.surface.push_back(flag[i] != 0 ? 1 : 0);
    if (view) {
      const auto [offset, velocity] = (*view)(k, i);
      data.position.push_back(p_.position[i] + offset);
      data.velocity.push_back(velocity);
    } else {
      data.position.push_back(p_.position[i]);
      data.velocity.push_back(p_.velocity[i]);
    }
    if (opt_.freeze_solid_density) data.reference_density.push_back(n0_solid[i]);
    ++k;
  }
  return data;
}

void FsiInterface::compute_load() {
  if (!initialized_) throw std::logic_error("FsiInterface: call initialize() first");
  // The ghosts as their owners hold them after the fluid step (positions, pressures, surface flags); rebuilt
  // when the fluid step removed particles that left the domain (the ghost plan then no longer fits).
  if (dist_ && dist_->n_ranks() > 1) dist_->renew(p_, {"position", opt_.pressure_field, opt_.flag_field});
  auto& load = p_.vector_field(field::load);
  const auto& flag = p_.scalar_field(opt_.flag_field);
  const auto& pressure = p_.scalar_field(opt_.pressure_field);
  const auto& n0_solid = p_.scalar_field(field::n0_solid);
  auto& prev_load = p_.vector_field(field::prev_load);
  auto& had_load = p_.scalar_field(field::had_load);
  std::fill(load.begin(), load.end(), Vec::Zero());
  for (auto& b : bodies_) {
    b.force.setZero();
    b.n_wetted = 0;
  }
  // The loaded particles (this rank's solid surface, eq. 48) and their neighbours among all particles.
  rows_.clear();
  for (std::size_t i = 0; i < p_.n_owned(); ++i)
    if (p_.kind[i] == ParticleKind::solid && flag[i] != 0 && !(opt_.exclude_clamped && p_.clamped[i]))
      rows_.push_back(static_cast<LocalIndex>(i));
  build_neighbour_list_of(p_.position, rows_, re_, rows_nl_, grid_);
  const Real volume = std::pow(dp_, dim);
  for (std::size_t q = 0; q < rows_.size(); ++q) {
    const auto i = static_cast<std::size_t>(rows_[q]);
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
    const Real n_tilde = n_total - n0_solid[i];  // eq. 51
    if (!wet || !(n_tilde > 0)) {
      had_load[i] = 0;  // a particle that falls dry starts afresh
      continue;
    }
    const Real n_norm = opt_.normalisation == FsiOptions::Normalisation::seed ? n_tilde : n0_;
    Vec f = -volume * (2.0 * dim / n_norm) * sum;  // eq. 50 times the particle volume, as -grad P
    if (opt_.load_relaxation < 1 && had_load[i] != 0) f = opt_.load_relaxation * f + (1 - opt_.load_relaxation) * prev_load[i];
    load[i] = f;
    prev_load[i] = f;
    had_load[i] = 1;
    const int slot = body_slot_[p_.body[i]];
    if (slot >= 0) {
      bodies_[static_cast<std::size_t>(slot)].force += f;
      ++bodies_[static_cast<std::size_t>(slot)].n_wetted;
    }
  }
  // Rows that are no surface rows any more (or clamped) carry no previous load either.
  for (std::size_t i = 0; i < p_.n_owned(); ++i)
    if (p_.kind[i] == ParticleKind::solid && load[i] == Vec::Zero()) had_load[i] = 0;
  reduce_bodies(true);
}

SolidLoadData FsiInterface::interface_load() const {
  SolidLoadData data;
  const auto& load = p_.vector_field(field::load);
  for (std::size_t i = 0; i < p_.n_owned(); ++i)
    if (p_.kind[i] == ParticleKind::solid) {
      data.ids.push_back(p_.global_id[i]);
      data.force.push_back(load[i]);
    }
  return data;
}

void FsiInterface::advance_solid(SolidSolver& solid, const Real t, const Real dt, const int n_sub) {
  if (n_sub < 1) throw std::invalid_argument(fmt::format("FsiInterface::advance_solid: n_sub = {} < 1", n_sub));
  const Real dts = dt / n_sub;
  solid.set_interface_load(interface_load());
  for (auto& b : bodies_) b.work_step = 0;
  const auto& load = p_.vector_field(field::load);
  auto& start_x = p_.vector_field(field::start_x);
  for (std::size_t i = 0; i < p_.n_owned(); ++i)
    if (p_.kind[i] == ParticleKind::solid) start_x[i] = p_.position[i];
  for (int k = 0; k < n_sub; ++k) {
    solid.advance(t + k * dts, dts);  // (may move particles between ranks: the fields go with them)
    // Symplectic Euler: the displacement of the sub-step is v_new dts, so F . v_new dts is the work.
    for (std::size_t i = 0; i < p_.n_owned(); ++i) {
      if (p_.kind[i] != ParticleKind::solid || load[i] == Vec::Zero()) continue;
      const int slot = body_slot_[p_.body[i]];
      if (slot >= 0) bodies_[static_cast<std::size_t>(slot)].work_step += dts * load[i].dot(p_.velocity[i]);
    }
  }
  reduce_bodies(false);
  for (auto& b : bodies_) b.work_total += b.work_step;
  auto& mean_v = p_.vector_field(field::mean_v);
  for (std::size_t i = 0; i < p_.n_owned(); ++i)
    if (p_.kind[i] == ParticleKind::solid) mean_v[i] = (p_.position[i] - start_x[i]) / dt;
  has_mean_v_ = true;
}

void FsiInterface::open_csv(const std::string& path, const bool append) {
  csv_.open(path, append ? std::ios::app : std::ios::trunc);
  csv_path_ = path;
  check_written(csv_, csv_path_, "interface table");
  if (!append) csv_ << (dim == 2 ? "time,body,fx,fy,work_step,work_total,wetted\n" : "time,body,fx,fy,fz,work_step,work_total,wetted\n");
}

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
  out.boolean(has_mean_v_);
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
  has_mean_v_ = in.boolean("the mean-velocity flag");
  bodies_.swap(bodies);
}

void FsiInterface::write_csv(const Real t) {
  if (!csv_.is_open()) return;
  for (const auto& b : bodies_)
  {
    csv_ << fmt::format("{:.9g},{}", t, b.name);
    for (int a = 0; a < dim; ++a) csv_ << fmt::format(",{:.9g}", b.force[a]);
    csv_ << fmt::format(",{:.9g},{:.9g},{}\n", b.work_step, b.work_total, b.n_wetted);
  }
  csv_.flush();
  check_written(csv_, csv_path_, "interface table");
}

}  // namespace mpsfsi
