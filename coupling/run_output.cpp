// The files a run writes as it goes (coupling/run_output.hpp).
#include "coupling/run_output.hpp"

#include "core/files.hpp"
#include "core/output_lock.hpp"
#include "core/stopwatch.hpp"
#include "core/collectives.hpp"
#include "coupling/rank0.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace mpsfsi {

bool appends(const RunSettings& settings, const std::string& file) {
  return std::find(settings.append_files.begin(), settings.append_files.end(), file) != settings.append_files.end();
}

RunOutput::RunOutput(const CaseSpec& spec, const ParticleSet& particles, const RunSettings& settings, MPI_Comm comm)
    : spec_(spec), settings_(settings), comm_(comm), rank_(rank_of(comm)), n_ranks_(size_of(comm)),
      eps_(1e-12 * std::max<Real>(1, spec.time.end)),
      writer_(settings.output_dir, "particles", rank_, n_ranks_),
      probes_(spec, particles, rank_ == 0 ? settings.output_dir + "/probes.csv" : std::string(),
              appends(settings, "probes.csv")),
      receivers_(spec, particles, rank_ == 0 ? settings.output_dir + "/receivers.csv" : std::string(),
                 appends(settings, "receivers.csv")),
      log_(settings.output_dir, appends(settings, "run.jsonl"), settings.quiet, rank_) {
  schedule_.next_frame = spec.output.interval;
  schedule_.next_probe = spec.output.probe_interval.value_or(0);
}

// output.fields names fields of this case: the solvers registered theirs (a case without a solid has no
// von_mises, for example), so the names are checked here rather than when the case is read.
void RunOutput::select_fields(const ParticleSet& particles) {
  std::vector<std::string> known;
  for (const auto& kv : particles.scalar_fields()) known.push_back(kv.first);
  for (const auto& kv : particles.vector_fields()) known.push_back(kv.first);
  // The internal fields (names starting with '_') last.
  std::stable_partition(known.begin(), known.end(), [](const std::string& name) { return name[0] != '_'; });
  for (const auto& name : spec_.output.fields)
    if (!particles.has_scalar_field(name) && !particles.has_vector_field(name))
      throw CaseError(fmt::format("{}: output.fields: '{}' is not a field of this case; expected some of: {} (the "
                                  "arrays velocity, kind, body, material, clamped and global_id are always written)",
                                  spec_.file, name.size() > 64 ? name.substr(0, 64) + "..." : name,
                                  fmt::join(known, ", ")));
  writer_.set_fields(spec_.output.fields);
}

void RunOutput::check_folder() const {
  if (settings_.output_lock == nullptr) return;
  const std::string lost = settings_.output_lock->lost();
  if (!lost.empty()) throw OutputError(lost);  // stopped_by_output adds that its files are gone
}

void RunOutput::write_frame(const ParticleSet& particles, const Real t, const std::size_t step,
                            const std::function<void()>& on_rank0_after) {
  const auto t0 = Clock::now();
  const std::vector<Real> probe_values =
      spec_.output.probe_interval ? std::vector<Real>{} : probes_.evaluate(particles, t, comm_);
  try {
    // Every rank writes its piece; once all are complete, rank 0 adds the frame to the series.
    on_every_rank(comm_, [&] {
      if (!log_.error().empty()) throw OutputError(log_.error());  // found on rank 0 alone, stops all ranks here
      if (rank_ == 0) check_folder();
      writer_.write_piece(particles, t);
    });
    on_rank0(comm_, [&] {
      writer_.commit_frame(t);
      if (!spec_.output.probe_interval) probes_.record(t, probe_values);
      if (on_rank0_after) on_rank0_after();
    });
    if (rank_ != 0) writer_.commit_frame(t);
  } catch (const OutputError& e) {
    throw OutputError(stopped_by_output(e.what(), t, step));
  }
  seconds_ += seconds_since(t0);
}

void RunOutput::record_rows(const ParticleSet& particles, const Real t) {
  receivers_.record_if_due(t, particles, comm_);
  if (!spec_.output.probe_interval || t < schedule_.next_probe - eps_) return;
  const std::vector<Real> values = probes_.evaluate(particles, t, comm_);
  on_rank0(comm_, [&] { probes_.record(t, values); });
  schedule_.next_probe = next_after(schedule_.next_probe, *spec_.output.probe_interval, t);
}

void RunOutput::record_initial_rows(const ParticleSet& particles, const Real t) {
  if (spec_.output.probe_interval) {
    const std::vector<Real> values = probes_.evaluate(particles, t, comm_);
    on_rank0(comm_, [&] { probes_.record(t, values); });
  }
  receivers_.record_if_due(t, particles, comm_);
}

std::string RunOutput::write_failure_frame(const ParticleSet& last_good, const Real t) {
  try {
    // A series never repeats a time: when the last good state is the last frame's (a failure in the first
    // steps after a frame), that frame is it.
    if (writer_.n_frames() > 0 && writer_.frames().back().first == t)
      return (std::filesystem::path(settings_.output_dir) / writer_.frames().back().second).string() + " (already written)";
    std::string frame;
    on_every_rank(comm_, [&] { writer_.write_piece(last_good, t); });
    on_rank0(comm_, [&] { frame = writer_.commit_frame(t); });
    if (rank_ != 0) writer_.commit_frame(t);
    return frame;
  } catch (const std::exception& e) {
    return std::string("(could not be written: ") + e.what() + ")";
  }
}

std::string RunOutput::stopped_by_output(const std::string& what, const Real t, const std::size_t step) {
  // A folder removed while a file was written: the write's error ("No such file") names the symptom, the
  // lock the cause.
  const std::string lost = settings_.output_lock != nullptr ? settings_.output_lock->lost() : std::string();
  const bool gone = !lost.empty();
  const std::string cause = gone && what.find(lost) == std::string::npos ? lost + " (" + what + ")" : what;
  const std::string frames =
      gone                     ? std::string("its files are gone with the folder")
      : writer_.n_frames() > 0 ? fmt::format("{} lists the {} complete frame(s) up to t = {:.6g} s", writer_.pvd_path(),
                                             writer_.n_frames(), writer_.frames().back().first)
                               : std::string("no frame was written");
  const std::string text = fmt::format("{}\nthe run stopped at t = {:.6g} s (step {}); {}", cause, t, step, frames);
  // May fail as well on a full disk: the message on stderr is the one that counts.
  log_.event(fmt::format("{{\"event\":\"failure\",\"step\":{},\"t\":{:.9g},\"diagnosis\":\"{}\"}}", step, t,
                         RunLog::json_escape(text)));
  return text;
}

void RunOutput::continue_series(const Real t, const std::size_t next_frame) {
  on_rank0(comm_, [&] {
    if (settings_.continue_series)
      writer_.adopt_existing(t, next_frame);
    else
      writer_.set_next_frame(next_frame);
  });
  if (n_ranks_ > 1) {  // every piece continues with rank 0's frame number
    unsigned long long next = writer_.next_frame();
    MPI_Bcast(&next, 1, MPI_UNSIGNED_LONG_LONG, 0, comm_);
    writer_.set_next_frame(next);
  }
}

Real RunOutput::next_after(Real due, const Real interval, const Real t) const {
  const Real behind = std::floor((t + eps_ - due) / interval) + 1;
  due += behind > 1 ? behind * interval : interval;
  return due > t + eps_ ? due : t + interval;
}

}  // namespace mpsfsi
