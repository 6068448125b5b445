// Distribution of the particles over MPI ranks: Zoltan2 MultiJagged part boxes as the ranks' regions (the outer
// faces moved to infinity), migration of particles between regions, ghosts within the halo width and the
// exchanges over the ghost plan. Zoltan2 (and Kokkos) stay inside this file.
#include "core/distribution.hpp"

#include "core/binary_io.hpp"
#include "core/collectives.hpp"
#include "core/stopwatch.hpp"

#include <Kokkos_Core.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Teuchos_ParameterList.hpp>
#include <Zoltan2_BasicVectorAdapter.hpp>
#include <Zoltan2_PartitioningProblem.hpp>

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace mpsfsi {

namespace {

constexpr Real inf = std::numeric_limits<Real>::infinity();

static_assert(std::is_same<GlobalId, long long>::value, "the Zoltan2 global ordinal below is long long");

/// Kokkos (Serial) must be up before Zoltan2's MultiJagged allocates its views; finalized at exit only if
/// started here (the same rule as the pressure solver's).
void ensure_kokkos() {
  if (Kokkos::is_initialized()) return;
  Kokkos::initialize();
  std::atexit([] {
    if (Kokkos::is_initialized()) Kokkos::finalize();
  });
}

/// A box that holds no point (and is at infinite distance from every point).
Box empty_box() {
  Box b;
  b.lo = Vec::Constant(inf);
  b.hi = Vec::Constant(-inf);
  return b;
}

Box all_space() {
  Box b;
  b.lo = Vec::Constant(-inf);
  b.hi = Vec::Constant(inf);
  return b;
}

bool is_empty(const Box& b) {
  for (int a = 0; a < dim; ++a)
    if (!(b.lo[a] < b.hi[a])) return true;
  return false;
}

/// Do the interiors of two boxes intersect?
bool interiors_overlap(const Box& a, const Box& b) {
  if (is_empty(a) || is_empty(b)) return false;
  for (int k = 0; k < dim; ++k)
    if (!(std::max(a.lo[k], b.lo[k]) < std::min(a.hi[k], b.hi[k]))) return false;
  return true;
}

/// Euclidean gap between two boxes (0 when they touch or overlap; infinite when one is empty).
Real box_gap(const Box& a, const Box& b) {
  if (is_empty(a) || is_empty(b)) return inf;
  Real s = 0;
  for (int k = 0; k < dim; ++k) {
    const Real g = std::max({Real(0), a.lo[k] - b.hi[k], b.lo[k] - a.hi[k]});
    s += g * g;
  }
  return std::sqrt(s);
}

bool finite(const Vec& x) { return x.allFinite(); }

/// The smallest global id over the ranks for which `bad` holds locally (LLONG_MAX: none). Collective.
GlobalId first_bad_id(MPI_Comm comm, const ParticleSet& p, const std::size_t n,
                      const std::function<bool(std::size_t)>& bad) {
  GlobalId local = LLONG_MAX;
  for (std::size_t i = 0; i < n; ++i)
    if (bad(i)) local = std::min(local, p.global_id[i]);
  GlobalId global = LLONG_MAX;
  MPI_Allreduce(&local, &global, 1, MPI_LONG_LONG, MPI_MIN, comm);
  return global;
}

/// Throws on every rank when a rank holds an owned particle with a non-finite position. Collective.
void check_positions(MPI_Comm comm, const ParticleSet& p, const std::size_t n) {
  const GlobalId bad = first_bad_id(comm, p, n, [&](std::size_t i) { return !finite(p.position[i]); });
  if (bad != LLONG_MAX)
    throw std::runtime_error("particle " + std::to_string(bad) +
                             " has a non-finite position: it cannot be assigned to a rank");
}

/// Asserts that every rank registered the same particle fields (packed particles must agree). Collective.
void check_layout(MPI_Comm comm, const ParticleSet& p) {
  const auto h = static_cast<unsigned long long>(std::hash<std::string>{}(p.field_layout()));
  unsigned long long both[2] = {h, ~h}, out[2] = {0, 0};
  MPI_Allreduce(both, out, 2, MPI_UNSIGNED_LONG_LONG, MPI_MAX, comm);
  assert(out[0] == h && ~out[1] == h && "every rank must register the same particle fields");
  (void)out;
}

int to_int(const std::size_t n) {
  assert(n <= static_cast<std::size_t>(INT_MAX) && "message too large for one MPI call");
  return static_cast<int>(n);
}

}  // namespace

bool Box::contains(const Vec& x) const {
  for (int a = 0; a < dim; ++a) {
    if (!(lo[a] <= x[a])) return false;
    if (!(x[a] < hi[a] || (x[a] == hi[a] && hi[a] == inf))) return false;
  }
  return true;
}

Real Box::distance(const Vec& x) const {
  if (is_empty(*this)) return inf;
  Real s = 0;
  for (int a = 0; a < dim; ++a) {
    const Real g = std::max({Real(0), lo[a] - x[a], x[a] - hi[a]});
    s += g * g;
  }
  return std::sqrt(s);
}

/// The ghost plan of the last build_ghosts() and a private communicator for this object's messages.
struct Distribution::Impl {
  MPI_Comm comm = MPI_COMM_NULL;  ///< duplicate of the user's communicator
  std::vector<std::vector<LocalIndex>> send_index;  ///< per rank: my owned particles it holds as ghosts
  std::vector<std::size_t> recv_count, recv_offset;  ///< per rank: its particles I hold as ghosts, where
  std::size_t plan_owned = 0, plan_ghost = 0;        ///< the set the plan was built for
  bool have_plan = false;
  std::vector<Vec> x_at_plan;                        ///< the owned particles' positions at build_ghosts()
  std::array<std::vector<LocalIndex>, 4> owned_of_kind;  ///< the owned particles of each kind at build_ghosts()
};

struct Distribution::Plan {
  std::vector<std::vector<LocalIndex>> send_index;
  std::vector<std::size_t> recv_count, recv_offset;
  std::size_t plan_owned = 0, plan_ghost = 0;
  bool have_plan = false;
  std::vector<Vec> x_at_plan;
  std::array<std::vector<LocalIndex>, 4> owned_of_kind;
};

std::shared_ptr<const Distribution::Plan> Distribution::save_plan() const {
  const Impl& m = *impl_;
  return std::make_shared<const Plan>(
      Plan{m.send_index, m.recv_count, m.recv_offset, m.plan_owned, m.plan_ghost, m.have_plan, m.x_at_plan, m.owned_of_kind});
}

void Distribution::restore_plan(const std::shared_ptr<const Plan>& plan) {
  if (!plan) throw std::logic_error("Distribution::restore_plan: no plan");
  Impl& m = *impl_;
  m.send_index = plan->send_index;
  m.recv_count = plan->recv_count;
  m.recv_offset = plan->recv_offset;
  m.plan_owned = plan->plan_owned;
  m.plan_ghost = plan->plan_ghost;
  m.have_plan = plan->have_plan;
  m.x_at_plan = plan->x_at_plan;
  m.owned_of_kind = plan->owned_of_kind;
}

Distribution::Distribution(MPI_Comm comm, const DistributionSettings& settings)
    : impl_(std::make_unique<Impl>()), comm_(comm), settings_(settings) {
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &n_ranks_);
  MPI_Comm_dup(comm_, &impl_->comm);
  if (!(settings_.halo_width >= 0))
    throw std::runtime_error("distribution: the halo width must be >= 0, not " + std::to_string(settings_.halo_width));
}

Distribution::~Distribution() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized && impl_->comm != MPI_COMM_NULL) MPI_Comm_free(&impl_->comm);
}

int Distribution::owner_of(const Vec& x) const {
  if (regions_.empty()) {
    assert(n_ranks_ == 1 && "owner_of before the first partition");
    return 0;
  }
  for (std::size_t r = 0; r < regions_.size(); ++r)
    if (regions_[r].contains(x)) return static_cast<int>(r);
  assert(!finite(x) && "the regions do not tile space");
  return -1;
}

// ---------------------------------------------------------------------------------------------------------------
// Partition

namespace {

/// Zoltan2 MultiJagged on the given points of this rank; returns one box per part (part p = rank p), as
/// Zoltan2 computed them (finite, over the points' bounding box). Collective.
std::vector<Box> zoltan_boxes(MPI_Comm comm, const int n_parts, const PartitionMethod method, const Vec* x,
                              const GlobalId* gid, const Real* w, const std::size_t n) {
  ensure_kokkos();
  using Types = Zoltan2::BasicUserTypes<Real, int, GlobalId>;
  using Adapter = Zoltan2::BasicVectorAdapter<Types>;

  // Coordinates: axis a of point i at x[i].data()[a], stride dim.
  const Real* base = n ? x->data() : nullptr;
  std::vector<const Real*> coords(dim);
  std::vector<int> coord_strides(dim, dim);
  for (int a = 0; a < dim; ++a) coords[a] = base ? base + a : nullptr;
  std::vector<const Real*> weights;
  std::vector<int> weight_strides;
  if (w) {
    weights.push_back(w);
    weight_strides.push_back(1);
  }
  Adapter adapter(static_cast<int>(n), gid, coords, coord_strides, weights, weight_strides);

  Teuchos::ParameterList params("mpsfsi distribution");
  params.set("algorithm", "multijagged");
  params.set("num_global_parts", n_parts);
  params.set("imbalance_tolerance", 1.01);
  params.set("mj_keep_part_boxes", true);
  if (method == PartitionMethod::rcb) params.set("mj_enable_rcb", true);

  const Teuchos::RCP<const Teuchos::Comm<int>> tcomm =
      Teuchos::rcp(new Teuchos::MpiComm<int>(Teuchos::opaqueWrapper(comm)));
  Zoltan2::PartitioningProblem<Adapter> problem(&adapter, &params, tcomm);
  problem.solve();
  const auto& parts = problem.getSolution().getPartBoxesView();

  std::vector<Box> boxes(static_cast<std::size_t>(n_parts), empty_box());
  for (const auto& b : parts) {
    const int id = b.getpId();
    assert(id >= 0 && id < n_parts && b.getDim() == dim);
    for (int a = 0; a < dim; ++a) {
      boxes[static_cast<std::size_t>(id)].lo[a] = b.getlmins()[a];
      boxes[static_cast<std::size_t>(id)].hi[a] = b.getlmaxs()[a];
    }
  }
  return boxes;
}

/// Turns Zoltan2's part boxes into regions that tile all space: on each axis the faces on the outside of the
/// partition (the smallest lo, the largest hi over the boxes) move to -inf / +inf. A box of zero width on an
/// axis the partition spans is an empty part (no points) and holds nothing. Zoltan2 leaves the axes it does not
/// cut at [0, 0] in every box: they become (-inf, inf). Returns false when the result overlaps (degenerate
/// input, e.g. all points on one plane across which the partition cuts).
bool extend_to_infinity(std::vector<Box>& boxes) {
  Vec gmin = Vec::Constant(inf), gmax = Vec::Constant(-inf);
  for (const auto& b : boxes) {
    gmin = gmin.cwiseMin(b.lo);
    gmax = gmax.cwiseMax(b.hi);
  }
  for (auto& b : boxes) {
    bool empty = false;
    for (int a = 0; a < dim; ++a) empty |= !(b.lo[a] <= b.hi[a]) || (b.lo[a] == b.hi[a] && gmin[a] < gmax[a]);
    if (empty) {
      b = empty_box();
      continue;
    }
    for (int a = 0; a < dim; ++a) {
      if (b.lo[a] == gmin[a]) b.lo[a] = -inf;
      if (b.hi[a] == gmax[a]) b.hi[a] = inf;
    }
  }
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      if (interiors_overlap(boxes[i], boxes[j])) return false;
  return true;
}

/// Each cut, a face coordinate c along an axis that boxes share (hi = c below it, lo = c above), moves into a
/// gap between the points on its two sides within `reach` of it (over all ranks): Zoltan2 places a cut at the
/// coordinate that splits the weight, which on a lattice lies within a plane of points, and the plane's points
/// then cross it as soon as they move a little. Of the gaps at least half as wide as the widest within reach,
/// the cut takes the middle of the one that moves the least weight across it. Collective.
void centre_cuts(MPI_Comm comm, std::vector<Box>& boxes, const Vec* x, const Real* w, const std::size_t n,
                 const Real reach) {
  if (!(reach > 0)) return;
  struct Cut {
    int axis;
    Real c;
  };
  std::vector<Cut> cuts;
  for (const Box& b : boxes)
    for (int a = 0; a < dim && !is_empty(b); ++a)
      if (std::isfinite(b.hi[a]) &&
          std::none_of(cuts.begin(), cuts.end(), [&](const Cut& k) { return k.axis == a && k.c == b.hi[a]; }))
        cuts.push_back({a, b.hi[a]});
  if (cuts.empty()) return;
  // Per cut, the points within reach in a box on either side of it: (cut, coordinate, weight).
  std::vector<Real> mine;
  for (std::size_t i = 0; i < n; ++i) {
    const auto in = std::find_if(boxes.begin(), boxes.end(), [&](const Box& b) { return b.contains(x[i]); });
    if (in == boxes.end()) continue;
    for (std::size_t k = 0; k < cuts.size(); ++k) {
      const int a = cuts[k].axis;
      if ((in->hi[a] == cuts[k].c || in->lo[a] == cuts[k].c) && std::abs(x[i][a] - cuts[k].c) <= reach)
        mine.insert(mine.end(), {static_cast<Real>(k), x[i][a], w ? w[i] : 1.0});
    }
  }
  const std::vector<Real> all = all_gather(comm, mine);
  for (std::size_t k = 0; k < cuts.size(); ++k) {
    std::vector<std::pair<Real, Real>> near;  // coordinate, weight
    for (std::size_t q = 0; q + 2 < all.size(); q += 3)
      if (static_cast<std::size_t>(all[q]) == k) near.emplace_back(all[q + 1], all[q + 2]);
    if (near.size() < 2) continue;
    std::sort(near.begin(), near.end());
    const Real c = cuts[k].c;
    Real widest = 0;
    for (std::size_t q = 0; q + 1 < near.size(); ++q) widest = std::max(widest, near[q + 1].first - near[q].first);
    if (!(widest > 0)) continue;
    // The weight below the cut, and below each gap: the weight a gap's middle moves across the cut.
    Real below_cut = 0;
    for (const auto& [xq, wq] : near) below_cut += xq < c ? wq : 0;
    Real below = 0, best_moved = std::numeric_limits<Real>::infinity(), best = c;
    for (std::size_t q = 0; q + 1 < near.size(); ++q) {
      below += near[q].second;
      if (near[q + 1].first - near[q].first < 0.5 * widest) continue;
      const Real moved = std::abs(below - below_cut);
      if (moved < best_moved) {
        best_moved = moved;
        best = 0.5 * (near[q].first + near[q + 1].first);
      }
    }
    const int a = cuts[k].axis;
    for (Box& b : boxes) {
      if (is_empty(b)) continue;
      if (b.hi[a] == c) b.hi[a] = best;
      if (b.lo[a] == c) b.lo[a] = best;
    }
  }
}

/// Regions from Zoltan2 on the points given by each rank, or (no points at all, or a degenerate partition
/// whose boxes cannot tile space) rank 0 owning all space; the cuts moved into gaps between the points within
/// `reach` (centre_cuts). Collective.
std::vector<Box> compute_regions(MPI_Comm comm, const int n_ranks, const PartitionMethod method, const Vec* x,
                                 const GlobalId* gid, const Real* w, const std::size_t n, const Real reach) {
  std::vector<Box> fallback(static_cast<std::size_t>(n_ranks), empty_box());
  fallback[0] = all_space();
  if (n_ranks == 1) return fallback;
  unsigned long long local = n, total = 0;
  MPI_Allreduce(&local, &total, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm);
  if (total == 0) return fallback;
  std::vector<Box> boxes = zoltan_boxes(comm, n_ranks, method, x, gid, w, n);
  if (!extend_to_infinity(boxes)) return fallback;
  centre_cuts(comm, boxes, x, w, n, reach);
  return boxes;
}

void check_weights(MPI_Comm comm, const ParticleSet& p, const std::vector<Real>& weights, const std::size_t first,
                   const std::size_t n) {
  if (weights.empty()) return;
  const GlobalId bad = first_bad_id(comm, p, n, [&](std::size_t i) {
    const Real wi = weights[first + i];
    return !(std::isfinite(wi) && wi >= 0);
  });
  if (bad != LLONG_MAX)
    throw std::runtime_error("particle " + std::to_string(bad) + " has a negative or non-finite partition weight");
}
}  // namespace

void Distribution::partition(ParticleSet& p, const std::vector<Real>& weights) {
  p.drop_ghosts();
  impl_->have_plan = false;
  const std::size_t n = p.n_owned();
  assert((weights.empty() || weights.size() == n) && "one weight per owned particle");
  const auto t0 = Clock::now();
  check_positions(impl_->comm, p, n);
  check_weights(impl_->comm, p, weights, 0, n);
  regions_ = compute_regions(impl_->comm, n_ranks_, settings_.method, p.position.data(), p.global_id.data(),
                             weights.empty() ? nullptr : weights.data(), n, settings_.skin);
  ++stats_.n_partitions;
  stats_.t_partition += seconds_since(t0);
  migrate(p);
}

void Distribution::distribute_replicated(ParticleSet& p, const std::vector<Real>& weights) {
  p.drop_ghosts();
  impl_->have_plan = false;
  const std::size_t n_all = p.n_owned();
  assert((weights.empty() || weights.size() == n_all) && "one weight per particle of the full set");
#ifndef NDEBUG
  {
    unsigned long long mine[2] = {n_all, ~static_cast<unsigned long long>(n_all)}, out[2];
    MPI_Allreduce(mine, out, 2, MPI_UNSIGNED_LONG_LONG, MPI_MAX, impl_->comm);
    assert(out[0] == n_all && ~out[1] == n_all && "distribute_replicated: every rank must hold the same set");
  }
#endif
  const auto t0 = Clock::now();
  check_positions(impl_->comm, p, n_all);
  // Zoltan2's input: a disjoint slice of the set per rank.
  const auto P = static_cast<unsigned long long>(n_ranks_), r = static_cast<unsigned long long>(rank_);
  const auto first = static_cast<std::size_t>(r * n_all / P), last = static_cast<std::size_t>((r + 1) * n_all / P);
  if (!weights.empty()) check_weights(impl_->comm, p, weights, 0, n_all);
  regions_ = compute_regions(impl_->comm, n_ranks_, settings_.method, p.position.data() + first,
                             p.global_id.data() + first, weights.empty() ? nullptr : weights.data() + first,
                             last - first, settings_.skin);
  ++stats_.n_partitions;
  if (n_ranks_ > 1) {
    std::vector<std::uint8_t> remove(n_all);
    for (std::size_t i = 0; i < n_all; ++i) remove[i] = owner_of(p.position[i]) != rank_;
    p.remove_if(remove);
  }
  stats_.n_migrated_out = 0;
  stats_.t_partition += seconds_since(t0);
}

Real Distribution::imbalance(const ParticleSet& p, const std::vector<Real>& weights) const {
  assert((weights.empty() || weights.size() == p.n_owned()) && "one weight per owned particle");
  Real work = 0;
  if (weights.empty())
    work = static_cast<Real>(p.n_owned());
  else
    for (const Real w : weights) work += w;
  Real max_work = 0, total = 0;
  MPI_Allreduce(&work, &max_work, 1, MPI_DOUBLE, MPI_MAX, impl_->comm);
  MPI_Allreduce(&work, &total, 1, MPI_DOUBLE, MPI_SUM, impl_->comm);
  if (total <= 0) return 0;
  return max_work / (total / n_ranks_) - 1;
}

// ---------------------------------------------------------------------------------------------------------------
// Migration

void Distribution::migrate(ParticleSet& p) {
  const auto t0 = Clock::now();
  p.drop_ghosts();
  impl_->have_plan = false;
  const std::size_t n = p.n_owned();
  check_positions(impl_->comm, p, n);
  stats_.n_migrated_out = 0;
  if (n_ranks_ == 1) {
    stats_.t_migrate += seconds_since(t0);
    return;
  }
  assert(!regions_.empty() && "migrate before the first partition");
  check_layout(impl_->comm, p);

  const auto P = static_cast<std::size_t>(n_ranks_);
  std::vector<std::vector<LocalIndex>> leaving(P);
  std::vector<std::uint8_t> remove(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const int q = owner_of(p.position[i]);
    assert(q >= 0);
    if (q != rank_) {
      leaving[static_cast<std::size_t>(q)].push_back(static_cast<LocalIndex>(i));
      remove[i] = 1;
    }
  }
  const std::size_t record = p.packed_size();
  std::vector<int> send_bytes(P), send_displ(P), recv_bytes(P), recv_displ(P);
  std::vector<char> send_buf;
  for (std::size_t q = 0; q < P; ++q) {
    send_displ[q] = to_int(send_buf.size());
    p.pack(leaving[q], send_buf);
    send_bytes[q] = to_int(leaving[q].size() * record);
    stats_.n_migrated_out += leaving[q].size();
  }
  MPI_Alltoall(send_bytes.data(), 1, MPI_INT, recv_bytes.data(), 1, MPI_INT, impl_->comm);
  std::size_t total = 0;
  for (std::size_t q = 0; q < P; ++q) {
    recv_displ[q] = to_int(total);
    total += static_cast<std::size_t>(recv_bytes[q]);
  }
  std::vector<char> recv_buf(total);
  MPI_Alltoallv(send_buf.data(), send_bytes.data(), send_displ.data(), MPI_BYTE, recv_buf.data(), recv_bytes.data(),
                recv_displ.data(), MPI_BYTE, impl_->comm);
  p.remove_if(remove);
  assert(total % record == 0);
  p.unpack_owned(recv_buf.data(), total / record);  // in order of sending rank, then of the sender's index
  stats_.t_migrate += seconds_since(t0);
}

// ---------------------------------------------------------------------------------------------------------------
// Ghosts

bool Distribution::needs_rebuild(const ParticleSet& p, const bool requested, const std::optional<ParticleKind> only) const {
  const Impl& m = *impl_;
  int rebuild = requested ? 1 : 0;
  if (n_ranks_ > 1) {
    if (!m.have_plan || p.n_owned() != m.plan_owned || p.n_ghost() != m.plan_ghost) {
      rebuild = 1;
    } else {
      Real moved2 = 0;
      if (only) {
        for (const LocalIndex i : m.owned_of_kind[static_cast<std::size_t>(*only)])
          moved2 = std::max(moved2, (p.position[static_cast<std::size_t>(i)] - m.x_at_plan[static_cast<std::size_t>(i)]).squaredNorm());
      } else {
        for (std::size_t i = 0; i < p.n_owned(); ++i) moved2 = std::max(moved2, (p.position[i] - m.x_at_plan[i]).squaredNorm());
      }
      // Two particles approach each other by at most twice the largest displacement.
      if (!(2 * std::sqrt(moved2) <= settings_.skin)) rebuild = 1;
    }
    MPI_Allreduce(MPI_IN_PLACE, &rebuild, 1, MPI_INT, MPI_MAX, m.comm);
  }
  return rebuild != 0;
}

int Distribution::ghost_owner(const std::size_t k) const {
  const Impl& m = *impl_;
  assert(m.have_plan && k < m.plan_ghost && "ghost_owner: no such ghost in the last build_ghosts()");
  // The last rank whose block of ghosts starts at or before k (blocks of ranks that sent none are empty).
  const auto it = std::upper_bound(m.recv_offset.begin(), m.recv_offset.end(), k);
  auto q = static_cast<std::size_t>(it - m.recv_offset.begin()) - 1;
  while (m.recv_count[q] == 0) --q;
  return static_cast<int>(q);
}

ParticleSet Distribution::gather(const ParticleSet& p, const int root) const {
  ParticleSet out = p;
  out.drop_ghosts();
  if (n_ranks_ == 1) return out;
  std::vector<LocalIndex> mine(p.n_owned());
  for (std::size_t i = 0; i < mine.size(); ++i) mine[i] = static_cast<LocalIndex>(i);
  std::vector<char> send;
  p.pack(mine, send);
  const int n_bytes = to_int(send.size());
  std::vector<int> counts(static_cast<std::size_t>(n_ranks_)), displs(static_cast<std::size_t>(n_ranks_), 0);
  MPI_Gather(&n_bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, root, impl_->comm);
  std::vector<char> all;
  if (rank_ == root) {
    std::size_t total = 0;
    for (std::size_t q = 0; q < counts.size(); ++q) {
      displs[q] = to_int(total);
      total += static_cast<std::size_t>(counts[q]);
    }
    all.resize(total);
  }
  MPI_Gatherv(send.data(), n_bytes, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, root, impl_->comm);
  std::vector<std::uint8_t> remove(out.size(), 1);
  out.remove_if(remove);  // keeps the fields, drops the particles
  if (rank_ != root) return out;
  out.unpack_owned(all.data(), all.size() / p.packed_size());
  return out;
}

void Distribution::save_state(BinaryWriter& out, const ParticleSet& p, const int root) const {
  unsigned long long owned = p.n_owned();
  std::vector<unsigned long long> counts(static_cast<std::size_t>(n_ranks_));
  MPI_Gather(&owned, 1, MPI_UNSIGNED_LONG_LONG, counts.data(), 1, MPI_UNSIGNED_LONG_LONG, root, impl_->comm);
  if (rank_ != root) return;
  out.section("distribution");
  out.i64(n_ranks_);
  out.u64(regions_.size());
  for (const Box& b : regions_) {
    out.value(b.lo);
    out.value(b.hi);
  }
  out.array(counts);
}

void Distribution::load_state(BinaryReader& in, ParticleSet& p) {
  in.expect_section("distribution");
  const auto n_saved = static_cast<int>(in.i64("the rank count"));
  const std::size_t n_regions = in.u64("the region count");
  if (n_regions > 1u << 20) in.fail("the distribution's regions are inconsistent");
  std::vector<Box> regions(n_regions);
  for (Box& b : regions) {
    b.lo = in.value<Vec>("a region");
    b.hi = in.value<Vec>("a region");
  }
  const auto counts = in.array<unsigned long long>("the owned counts");
  unsigned long long total = 0;
  for (const auto c : counts) total += c;
  if (counts.size() != static_cast<std::size_t>(n_saved) || total != p.size())
    in.fail("the distribution's counts do not match the particles");
  if (n_saved != n_ranks_ || (n_ranks_ > 1 && regions.size() != static_cast<std::size_t>(n_ranks_))) {
    distribute_replicated(p);
    return;
  }
  p.drop_ghosts();
  impl_->have_plan = false;
  if (n_ranks_ > 1) regions_ = regions;
  std::size_t begin = 0;
  for (int q = 0; q < rank_; ++q) begin += static_cast<std::size_t>(counts[static_cast<std::size_t>(q)]);
  const std::size_t end = begin + static_cast<std::size_t>(counts[static_cast<std::size_t>(rank_)]);
  std::vector<std::uint8_t> remove(p.size(), 1);
  for (std::size_t i = begin; i < end; ++i) remove[i] = 0;
  p.remove_if(remove);
}

void Distribution::build_ghosts(ParticleSet& p) {
  const auto t0 = Clock::now();
  p.drop_ghosts();
  Impl& m = *impl_;
  const auto P = static_cast<std::size_t>(n_ranks_);
  m.send_index.assign(P, {});
  m.recv_count.assign(P, 0);
  m.recv_offset.assign(P, 0);
  ++stats_.n_ghost_builds;
  m.plan_owned = p.n_owned();
  m.x_at_plan.assign(p.position.begin(), p.position.begin() + static_cast<std::ptrdiff_t>(p.n_owned()));
  for (auto& list : m.owned_of_kind) list.clear();
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    m.owned_of_kind[static_cast<std::size_t>(p.kind[i])].push_back(static_cast<LocalIndex>(i));
  m.plan_ghost = 0;
  m.have_plan = true;
  if (n_ranks_ == 1) {
    stats_.t_halo += seconds_since(t0);
    return;
  }
  assert(!regions_.empty() && "build_ghosts before the first partition");
  check_layout(m.comm, p);

  // Candidates: ranks whose region lies within the halo width of my particles' bounding box.
  const std::size_t n = p.n_owned();
  Box mine = empty_box();
  if (n > 0) {
    mine.lo = mine.hi = p.position[0];
    for (std::size_t i = 1; i < n; ++i) {
      mine.lo = mine.lo.cwiseMin(p.position[i]);
      mine.hi = mine.hi.cwiseMax(p.position[i]);
    }
  }
  const Real h = settings_.halo_width;
  for (std::size_t q = 0; q < P; ++q) {
    if (static_cast<int>(q) == rank_ || n == 0) continue;
    const Box& region = regions_[q];
    // A box of one point (n == 1) counts as empty for box_gap: test the particles directly then.
    if (n > 1 && !is_empty(mine) && box_gap(mine, region) > h) continue;
    for (std::size_t i = 0; i < n; ++i)
      if (region.distance(p.position[i]) <= h) m.send_index[q].push_back(static_cast<LocalIndex>(i));
  }

  std::vector<int> send_count(P), recv_count(P);
  for (std::size_t q = 0; q < P; ++q) send_count[q] = to_int(m.send_index[q].size());
  MPI_Alltoall(send_count.data(), 1, MPI_INT, recv_count.data(), 1, MPI_INT, m.comm);

  const std::size_t record = p.packed_size();
  std::vector<std::vector<char>> send_buf(P), recv_buf(P);
  std::vector<MPI_Request> requests;
  std::size_t offset = 0;
  for (std::size_t q = 0; q < P; ++q) {
    m.recv_count[q] = static_cast<std::size_t>(recv_count[q]);
    m.recv_offset[q] = offset;
    offset += m.recv_count[q];
    if (recv_count[q] == 0) continue;
    recv_buf[q].resize(m.recv_count[q] * record);
    requests.emplace_back();
    MPI_Irecv(recv_buf[q].data(), to_int(recv_buf[q].size()), MPI_BYTE, static_cast<int>(q), 1, m.comm,
              &requests.back());
  }
  for (std::size_t q = 0; q < P; ++q) {
    if (m.send_index[q].empty()) continue;
    p.pack(m.send_index[q], send_buf[q]);
    stats_.halo_bytes += send_buf[q].size();
    requests.emplace_back();
    MPI_Isend(send_buf[q].data(), to_int(send_buf[q].size()), MPI_BYTE, static_cast<int>(q), 1, m.comm,
              &requests.back());
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  for (std::size_t q = 0; q < P; ++q)
    if (m.recv_count[q] > 0) p.unpack_ghosts(recv_buf[q].data(), m.recv_count[q]);
  m.plan_ghost = offset;
  assert(p.n_ghost() == offset && p.n_owned() == m.plan_owned);
  stats_.t_halo += seconds_since(t0);
}

namespace {
std::vector<ParticleSet::RealArray> resolve(ParticleSet& p, const std::vector<std::string>& fields, int& width) {
  std::vector<ParticleSet::RealArray> arrays;
  width = 0;
  for (const auto& name : fields) {
    arrays.push_back(p.real_array(name));
    width += arrays.back().components;
  }
  return arrays;
}
}  // namespace

namespace {
/// Sends send_buf[q] to every rank q with a non-empty buffer and receives recv_buf[q] (already sized) from
/// every rank q with a non-empty one; returns the bytes sent.
std::size_t swap_buffers(MPI_Comm comm, const int tag, const std::vector<std::vector<Real>>& send_buf,
                         std::vector<std::vector<Real>>& recv_buf) {
  std::vector<MPI_Request> requests;
  requests.reserve(send_buf.size() + recv_buf.size());
  std::size_t bytes = 0;
  for (std::size_t q = 0; q < recv_buf.size(); ++q) {
    if (recv_buf[q].empty()) continue;
    requests.emplace_back();
    MPI_Irecv(recv_buf[q].data(), to_int(recv_buf[q].size()), MPI_DOUBLE, static_cast<int>(q), tag, comm,
              &requests.back());
  }
  for (std::size_t q = 0; q < send_buf.size(); ++q) {
    if (send_buf[q].empty()) continue;
    bytes += send_buf[q].size() * sizeof(Real);
    requests.emplace_back();
    MPI_Isend(send_buf[q].data(), to_int(send_buf[q].size()), MPI_DOUBLE, static_cast<int>(q), tag, comm,
              &requests.back());
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  return bytes;
}
}  // namespace

bool Distribution::renew(ParticleSet& p, const std::vector<std::string>& fields, const std::optional<ParticleKind> only,
                         const bool requested, const std::function<void()>& before_ghosts) {
  if (!needs_rebuild(p, requested, only)) {
    exchange_ghosts(p, fields, only);
    return false;
  }
  p.drop_ghosts();
  migrate(p);
  if (before_ghosts) before_ghosts();
  build_ghosts(p);
  return true;
}

void Distribution::exchange_ghosts(ParticleSet& p, const std::vector<std::string>& fields,
                                   const std::optional<ParticleKind> only) {
  transfer(p, fields, false, only);
}

void Distribution::reverse_sum(ParticleSet& p, const std::vector<std::string>& fields) { transfer(p, fields, true); }

void Distribution::transfer(ParticleSet& p, const std::vector<std::string>& fields, const bool to_owners,
                            const std::optional<ParticleKind> only) {
  const auto t0 = Clock::now();
  int width = 0;
  const auto arrays = resolve(p, fields, width);
  if (n_ranks_ == 1 || fields.empty()) return;
  Impl& m = *impl_;
  // Checked also in Release: a stale plan would read and write past the arrays.
  if (!(m.have_plan && p.n_owned() == m.plan_owned && p.n_ghost() == m.plan_ghost))
    throw std::logic_error("exchange_ghosts and reverse_sum need the particle set of the last build_ghosts() (call renew)");
  const auto P = static_cast<std::size_t>(n_ranks_);
  const std::size_t first_ghost = p.n_owned();
  // The particles shared with rank q: my owned ones it holds as ghosts, or my ghosts of its particles (with
  // `only`, those of that kind: a ghost has its owner's kind, so both sides pick the same particles in the same
  // order).
  const auto taken = [&](const std::size_t i) { return !only || p.kind[i] == *only; };
  const auto each = [&](const std::size_t q, const bool ghosts, auto&& f) {
    if (ghosts) {
      for (std::size_t k = 0; k < m.recv_count[q]; ++k)
        if (taken(first_ghost + m.recv_offset[q] + k)) f(first_ghost + m.recv_offset[q] + k);
    } else {
      for (const LocalIndex i : m.send_index[q])
        if (taken(static_cast<std::size_t>(i))) f(static_cast<std::size_t>(i));
    }
  };
  const auto count = [&](const std::size_t q, const bool ghosts) {
    if (!only) return ghosts ? m.recv_count[q] : m.send_index[q].size();
    std::size_t n = 0;
    each(q, ghosts, [&](std::size_t) { ++n; });
    return n;
  };
  // Owners to ghosts (values replaced), or ghosts back to their owners (values added, ghosts zeroed).
  const bool send_ghosts = to_owners;
  std::vector<std::vector<Real>> send_buf(P), recv_buf(P);
  for (std::size_t q = 0; q < P; ++q) {
    recv_buf[q].resize(count(q, !send_ghosts) * static_cast<std::size_t>(width));
    auto& buf = send_buf[q];
    buf.reserve(count(q, send_ghosts) * static_cast<std::size_t>(width));
    each(q, send_ghosts, [&](const std::size_t i) {
      for (const auto& a : arrays)
        for (int c = 0; c < a.components; ++c) {
          Real& v = a.data[i * a.components + c];
          buf.push_back(v);
          if (to_owners) v = 0;
        }
    });
  }
  stats_.halo_bytes += swap_buffers(m.comm, to_owners ? 3 : 2, send_buf, recv_buf);
  for (std::size_t q = 0; q < P; ++q) {  // in rank order: the sums come out the same on every run
    const Real* src = recv_buf[q].data();
    each(q, !send_ghosts, [&](const std::size_t i) {
      for (const auto& a : arrays)
        for (int c = 0; c < a.components; ++c) {
          Real& v = a.data[i * a.components + c];
          v = to_owners ? v + *src++ : *src++;
        }
    });
  }
  stats_.t_halo += seconds_since(t0);
}

}  // namespace mpsfsi
