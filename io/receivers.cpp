// Receiver stencils and receivers.csv (io/receivers.hpp).
#include "io/receivers.hpp"

#include "core/point_stencil.hpp"
#include "core/text.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace mpsfsi {

ReceiverWriter::ReceiverWriter(const CaseSpec& spec, const ParticleSet& particles, const std::string& path,
                               const bool append)
    : interval_(spec.receivers.interval) {
  for (const auto& rs : spec.receivers.points) {
    std::vector<std::size_t> candidates;
    for (std::size_t i = 0; i < particles.size(); ++i)
      if (particles.kind[i] == ParticleKind::solid && particles.bodies[particles.body[i]].name == rs.body)
        candidates.push_back(i);
    if (candidates.empty())
      throw CaseError(fmt::format("{}: receiver '{}': body '{}' is not a solid body with particles", spec.file, rs.name,
                                  rs.body));
    PointStencil st;
    try {
      st = interpolation_stencil(particles.position, candidates, rs.position, spec.receivers.radius);
    } catch (const std::invalid_argument& e) {
      throw CaseError(fmt::format("{}: receiver '{}' at {} on body '{}': {}", spec.file, rs.name, show_point(rs.position),
                                  rs.body, e.what()));
    }
    Receiver r;
    for (std::size_t q = 0; q < st.index.size(); ++q) {
      const std::size_t i = st.index[q];
      r.id.push_back(particles.global_id[i]);
      r.at.push_back(static_cast<LocalIndex>(i));
      r.x0.push_back(particles.position[i]);
      r.phi.push_back(st.weight[q]);
    }
    receivers_.push_back(std::move(r));
    for (int a = 0; a < dim; ++a) columns_.push_back(rs.name + "_u" + "xyz"[a]);
  }
  if (receivers_.empty() || path.empty()) return;
  out_.open(path, append ? std::ios::app : std::ios::trunc);
  path_ = path;
  check_written(out_, path_, "receiver table");
  if (append) return;
  out_ << "time";
  for (const auto& c : columns_) out_ << "," << c;
  out_ << "\n";
}

void ReceiverWriter::save_state(BinaryWriter& w) const {
  w.section("receivers");
  w.u64(receivers_.size());
  w.f64(next_);
  w.boolean(started_);
  w.u64(rows_);
}

void ReceiverWriter::load_state(BinaryReader& r) {
  r.expect_section("receivers");
  if (r.u64("the receiver count") != receivers_.size()) r.fail("the checkpoint's case has another number of receivers");
  next_ = r.f64("the next receiver row time");
  started_ = r.boolean("the receivers' started flag");
  rows_ = r.u64("the receiver rows");
}

void ReceiverWriter::resolve(const ParticleSet& p) const {
  bool moved = false;
  for (const auto& r : receivers_)
    for (std::size_t q = 0; q < r.id.size() && !moved; ++q) {
      const LocalIndex i = r.at[q];
      moved = i >= 0 && (static_cast<std::size_t>(i) >= p.n_owned() || p.global_id[static_cast<std::size_t>(i)] != r.id[q]);
      moved = moved || (i < 0 && p.local_index(r.id[q]) >= 0);
    }
  if (!moved) return;
  for (const auto& r : receivers_)
    for (std::size_t q = 0; q < r.id.size(); ++q) {
      const LocalIndex i = p.local_index(r.id[q]);
      r.at[q] = i >= 0 && static_cast<std::size_t>(i) < p.n_owned() ? i : -1;  // owned here, or another rank's
    }
}

std::vector<Vec> ReceiverWriter::evaluate(const ParticleSet& p, MPI_Comm comm) const {
  resolve(p);
  // Per receiver: the sum over this rank's owned stencil particles and their count, then summed over the ranks.
  std::vector<Real> sums;
  for (const auto& r : receivers_) {
    Vec s = Vec::Zero();
    Real found = 0;
    for (std::size_t q = 0; q < r.id.size(); ++q) {
      if (r.at[q] < 0) continue;
      s += r.phi[q] * (p.position[static_cast<std::size_t>(r.at[q])] - r.x0[q]);
      found += 1;
    }
    for (int a = 0; a < dim; ++a) sums.push_back(s[a]);
    sums.push_back(found);
  }
  int size = 1;
  if (comm != MPI_COMM_NULL) MPI_Comm_size(comm, &size);
  if (size > 1 && !sums.empty()) MPI_Allreduce(MPI_IN_PLACE, sums.data(), static_cast<int>(sums.size()), MPI_DOUBLE, MPI_SUM, comm);
  std::vector<Vec> u;
  u.reserve(receivers_.size());
  for (std::size_t k = 0; k < receivers_.size(); ++k) {
    const Real* v = &sums[k * (dim + 1)];
    if (static_cast<std::size_t>(v[dim]) != receivers_[k].id.size())
      throw std::logic_error("ReceiverWriter: a receiver particle disappeared");
    u.push_back(Eigen::Map<const Vec>(v));
  }
  return u;
}

void ReceiverWriter::record_if_due(const Real t, const ParticleSet& particles, MPI_Comm comm) {
  if (receivers_.empty()) return;
  if (started_ && interval_ && t < next_ - 1e-9 * *interval_) return;
  if (interval_) {
    next_ = started_ ? next_ + *interval_ : t + *interval_;
    while (next_ <= t + 1e-9 * *interval_) next_ += *interval_;
  }
  started_ = true;
  const std::vector<Vec> values = evaluate(particles, comm);  // on every rank: a collective
  if (!out_.is_open()) return;
  out_ << fmt::format("{:.9g}", t);
  for (const Vec& u : values)
    for (int a = 0; a < dim; ++a) out_ << fmt::format(",{:.9g}", u[a]);
  out_ << "\n";
  if (++rows_ % 256 == 0) flush();
}

}  // namespace mpsfsi
