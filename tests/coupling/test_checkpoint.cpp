// Checkpoint building blocks (label unit): the binary state streams, ParticleSet save/load, the case
// comparison of a restart, and the checkpoint file's checks (round trip, truncated, damaged, not a
// checkpoint). The bit-for-bit restarts of whole runs are script tests (tests/restart).
#include "core/binary_io.hpp"
#include "core/particles.hpp"
#include "core/version.hpp"
#include "coupling/checkpoint.hpp"
#include "io/case.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

using namespace mpsfsi;

namespace {

std::string temp_path(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "mpsfsi_test_checkpoint";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void spit(const std::string& path, const std::string& data) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << data;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(BinaryStreams, RoundTripAndErrors) {
  BinaryWriter w;
  w.section("a");
  w.u64(42);
  w.f64(-0.1);
  w.string("hello");
  w.boolean(true);
  w.array(std::vector<Vec>{Vec(1, 2), Vec(3, 4)});
  w.array(std::vector<std::uint8_t>{1, 0, 1});
  const std::string data = w.bytes();

  BinaryReader r(data, "test.bin");
  r.expect_section("a");
  EXPECT_EQ(r.u64("x"), 42u);
  EXPECT_EQ(r.f64("x"), -0.1);
  EXPECT_EQ(r.string("x"), "hello");
  EXPECT_TRUE(r.boolean("x"));
  const auto v = r.array<Vec>("x", 2);
  EXPECT_EQ(v[1], Vec(3, 4));
  EXPECT_EQ(r.array<std::uint8_t>("x"), (std::vector<std::uint8_t>{1, 0, 1}));
  EXPECT_TRUE(r.at_end());
  EXPECT_THAT(error_of([&] { r.u64("the step"); }), ::testing::HasSubstr("test.bin: truncated or damaged: the step"));

  BinaryReader wrong_section(data, "test.bin");
  EXPECT_THAT(error_of([&] { wrong_section.expect_section("b"); }), ::testing::HasSubstr("expected section 'b'"));
  BinaryReader wrong_type(data, "test.bin");
  wrong_type.expect_section("a");
  wrong_type.u64("x");
  wrong_type.f64("x");
  wrong_type.string("x");
  wrong_type.boolean("x");
  EXPECT_THAT(error_of([&] { wrong_type.array<double>("positions"); }), ::testing::HasSubstr("positions: element size 16"));
  const std::string cut = data.substr(0, data.size() - 2);
  BinaryReader short_reader(cut, "cut.bin");
  EXPECT_THROW(
      {
        short_reader.expect_section("a");
        short_reader.u64("x");
        short_reader.f64("x");
        short_reader.string("x");
        short_reader.boolean("x");
        short_reader.array<Vec>("x");
        short_reader.array<std::uint8_t>("x");
      },
      StateFormatError);
}

ParticleSet make_set() {
  ParticleSet p;
  p.bodies = {{"water", ParticleKind::fluid, 0}, {"box", ParticleKind::wall, -1}};
  p.add_scalar_field("pressure");
  p.add_vector_field("load");
  for (int i = 0; i < 10; ++i) p.add(Vec(0.1 * i, 0.2 * i), Vec(i, -i), i < 7 ? ParticleKind::fluid : ParticleKind::wall, i < 7 ? 0 : 1, i < 7 ? 0 : -1);
  return p;
}

TEST(ParticleSetState, RoundTripOfAReorderedAndReducedSet) {
  ParticleSet a = make_set();
  for (std::size_t i = 0; i < a.size(); ++i) {
    a.scalar_field("pressure")[i] = 100.0 + static_cast<Real>(i) / 3;
    a.vector_field("load")[i] = Vec(1.0 / (1 + static_cast<Real>(i)), 2);
  }
  a.reorder({9, 8, 7, 6, 5, 4, 3, 2, 1, 0});
  std::vector<std::uint8_t> remove(a.size(), 0);
  remove[3] = 1;
  a.remove_if(remove);
  BinaryWriter w;
  a.save_state(w);

  ParticleSet b = make_set();  // the initial set of the same case
  auto& pressure = b.scalar_field("pressure");  // references stay valid through load_state
  BinaryReader r(w.bytes(), "ck");
  b.load_state(r);
  EXPECT_TRUE(r.at_end());
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b.position[i], a.position[i]);
    EXPECT_EQ(b.velocity[i], a.velocity[i]);
    EXPECT_EQ(b.kind[i], a.kind[i]);
    EXPECT_EQ(b.global_id[i], a.global_id[i]);
    EXPECT_EQ(pressure[i], a.scalar_field("pressure")[i]);
    EXPECT_EQ(b.vector_field("load")[i], a.vector_field("load")[i]);
  }
}

TEST(ParticleSetState, OtherFieldsOrBodiesAreRefusedAndLeaveTheSetUnchanged) {
  ParticleSet a = make_set();
  a.add_scalar_field("rotation");
  BinaryWriter w;
  a.save_state(w);
  ParticleSet b = make_set();
  b.position[0] = Vec(7, 7);
  BinaryReader r(w.bytes(), "ck");
  EXPECT_THAT(error_of([&] { b.load_state(r); }),
              ::testing::HasSubstr("the checkpoint has the scalar particle field 'rotation', which this run does not have"));
  EXPECT_EQ(b.position[0], Vec(7, 7));

  ParticleSet c = make_set();
  c.bodies[1].name = "tank";
  BinaryWriter w2;
  make_set().save_state(w2);
  BinaryReader r2(w2.bytes(), "ck");
  EXPECT_THAT(error_of([&] { c.load_state(r2); }), ::testing::HasSubstr("body 1 of the checkpoint is 'box'"));
}

const char* case_yaml = R"(name: tiny
description: "tiny"
source: "test"
dp: 0.01
domain: {min: [-0.1, -0.1], max: [0.5, 0.5]}
time: {end: 1.0, cfl: 0.2}
gravity: [0, -9.81]
materials:
  water: {type: fluid, rho: 1000, nu: 1.0e-6, c: 20, kappa: 0.2}
bodies:
  - {name: water, kind: fluid, material: water, rectangle: {min: [0, 0], max: [0.1, 0.1]}}
walls:
  - {name: box, type: box, rectangle: {min: [0, 0], max: [0.2, 0.2]}}
output: {interval: 0.01}
)";

TEST(CaseDifferences, OnlyKeysARestartMayNotChangeCount) {
  const std::string base = parse_case(case_yaml, "tiny.yaml").resolved_yaml;
  EXPECT_TRUE(case_differences(base, parse_case(case_yaml, "tiny.yaml", {"time.end=3", "output.interval=0.05",
                                                                         "description=other"})
                                         .resolved_yaml)
                  .empty());
  // The same number written otherwise (--dp writes 17 digits) is the same value.
  EXPECT_TRUE(case_differences(base, parse_case(case_yaml, "tiny.yaml", {"dp=0.010000000000000000208"}).resolved_yaml).empty());
  const auto d = case_differences(base, parse_case(case_yaml, "tiny.yaml", {"dp=0.02", "time.dt_max=0.002"}).resolved_yaml);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].text(), "dp: 0.01 vs 0.02");
  EXPECT_EQ(d[1].text(), "time.dt_max: (absent) vs 0.002");
  EXPECT_FALSE(key_under(d[0].key, restart_tunable_keys()));
  EXPECT_TRUE(key_under(d[1].key, restart_tunable_keys()));
  EXPECT_TRUE(key_under("output.fields[2]", restart_free_keys()));
  EXPECT_FALSE(key_under("time.endless", restart_free_keys()));
}

CheckpointInfo sample_info() {
  CheckpointInfo info;
  info.case_name = "tiny";
  info.case_file = "tiny.yaml";
  info.case_dir = "/cases";
  info.resolved_yaml = "name: tiny\n";
  info.time = 0.25;
  info.step = 250;
  info.n_particles = 10;
  info.next_frame = 26;
  info.frames = {{0.0, "particles_000000.vtu"}, {0.01, "particles_000001.vtu"}};
  info.outputs = {{"probes.csv", 123, 456}};
  info.written_at = "now";
  return info;
}

TEST(CheckpointFile, RoundTripAndRefusals) {
  const std::string path = temp_path("round_trip.chk");
  write_checkpoint(path, sample_info(), std::string("STATE"));
  const Checkpoint c = read_checkpoint(path, MPI_COMM_SELF);
  EXPECT_EQ(c.info.code_version, code_version());
  EXPECT_EQ(c.info.case_name, "tiny");
  EXPECT_EQ(c.info.time, 0.25);
  EXPECT_EQ(c.info.step, 250u);
  EXPECT_EQ(c.info.next_frame, 26u);
  ASSERT_EQ(c.info.frames.size(), 2u);
  EXPECT_EQ(c.info.frames[1].second, "particles_000001.vtu");
  ASSERT_EQ(c.info.outputs.size(), 1u);
  EXPECT_EQ(c.info.outputs[0].hash, 456u);
  EXPECT_EQ(c.data.substr(c.payload_begin, c.payload_end - c.payload_begin), "STATE");

  const std::string data = slurp(path);
  const std::string bad = temp_path("bad.chk");
  spit(bad, data.substr(0, data.size() / 2));
  EXPECT_THAT(error_of([&] { read_checkpoint(bad, MPI_COMM_SELF); }), ::testing::HasSubstr("is truncated"));
  std::string damaged = data;
  damaged[data.size() / 2] ^= 0x20;
  spit(bad, damaged);
  EXPECT_THAT(error_of([&] { read_checkpoint(bad, MPI_COMM_SELF); }), ::testing::HasSubstr("is damaged"));
  spit(bad, "name: tiny\n");
  EXPECT_THAT(error_of([&] { read_checkpoint(bad, MPI_COMM_SELF); }), ::testing::HasSubstr("is not an mpsfsi checkpoint"));
  EXPECT_THAT(error_of([&] { read_checkpoint(temp_path("none.chk"), MPI_COMM_SELF); }),
              ::testing::HasSubstr("no such checkpoint file"));
  // Every refusal is a CaseError (exit code 2).
  EXPECT_THROW(read_checkpoint(bad, MPI_COMM_SELF), CaseError);

  // A folder: its latest checkpoint by the time in the name.
  const auto dir = std::filesystem::path(temp_path("folder"));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  CheckpointInfo later = sample_info();
  later.time = 10.5;
  write_checkpoint((dir / checkpoint_file_name(2.0)).string(), sample_info(), "A");
  write_checkpoint((dir / checkpoint_file_name(10.5)).string(), later, "B");
  EXPECT_EQ(read_checkpoint(dir.string(), MPI_COMM_SELF).info.time, 10.5);
}

}  // namespace

// A restart removes the checkpoints after its own (a branch), never its own: the name rounds the time to 9
// digits, here up (0.1002211466 -> 0.100221147), and the name of the time itself is not later.
TEST(CheckpointFile, ItsOwnNameIsNotLaterThanItsTime) {
  const Real t = 0.1002211466;
  EXPECT_EQ(checkpoint_file_name(t), "checkpoint_0.100221147.chk");
  EXPECT_FALSE(is_later_checkpoint(checkpoint_file_name(t), t));
  EXPECT_FALSE(is_later_checkpoint(checkpoint_file_name(t - 1e-6), t));
  EXPECT_TRUE(is_later_checkpoint(checkpoint_file_name(t + 1e-8), t));
  EXPECT_FALSE(is_later_checkpoint("particles_000001.vtu", t));
}
