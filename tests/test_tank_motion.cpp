// Unit tests of the prescribed tank motion (core/tank_motion): sine roll, measured angle table
// (interpolation, centred-difference angular velocity, reading), rigid placement about the pivot; the
// clamped solid particles that follow the tank (solid/) and the tank-frame displacement probe (io/).
#include "core/tank_motion.hpp"
#include "io/probes.hpp"
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"
#include "support/spec_builders.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

using namespace mpsfsi;
namespace fs = std::filesystem;

namespace {

constexpr Real deg = pi / 180;

TankMotion sine(const Real amplitude, const Real period, const Vec& pivot = Vec(0.3, 0)) {
  TankMotionParams q;
  q.type = TankMotionParams::Type::sine_roll;
  q.amplitude = amplitude;
  q.period = period;
  q.pivot = pivot;
  return TankMotion(q);
}

TankMotionParams table_params(std::vector<Real> t, std::vector<Real> a) {
  TankMotionParams q;
  q.type = TankMotionParams::Type::table;
  q.time = std::move(t);
  q.angle = std::move(a);
  return q;
}

/// A temporary file with `text`, removed at the end of the test.
struct TempFile {
  fs::path path;
  explicit TempFile(const std::string& text, const std::string& name = "roll.csv") {
    path = fs::temp_directory_path() / fs::path("mpsfsi_tank_motion_" + std::to_string(::getpid()) + "_" + name);
    std::ofstream(path) << text;
  }
  ~TempFile() {
    std::error_code ec;
    fs::remove(path, ec);
  }
};

}  // namespace

TEST(TankMotion, NoneStandsStill) {
  const TankMotion m;
  EXPECT_FALSE(m.moving());
  EXPECT_EQ(m.angle(1.3), 0);
  EXPECT_EQ(m.angular_velocity(1.3), 0);
  EXPECT_TRUE(std::isinf(m.end_time()));
  EXPECT_EQ(m.place(Vec(0.1, 0.2), m.angle(0.5)), Vec(0.1, 0.2));
}

TEST(TankMotion, SineRollAngleAndExactDerivative) {
  const TankMotion m = sine(4 * deg, 1.211);
  EXPECT_TRUE(m.moving());
  EXPECT_DOUBLE_EQ(m.angle(0), 0);
  EXPECT_NEAR(m.angle(1.211 / 4), 4 * deg, 1e-15);
  EXPECT_NEAR(m.angle(3 * 1.211 / 4), -4 * deg, 1e-15);
  EXPECT_NEAR(m.angular_velocity(0), 4 * deg * 2 * pi / 1.211, 1e-14);
  for (const Real t : {0.1, 0.77, 2.5, 9.3}) {
    const Real h = 1e-6;
    EXPECT_NEAR(m.angular_velocity(t), (m.angle(t + h) - m.angle(t - h)) / (2 * h), 1e-8) << "t = " << t;
  }
  EXPECT_THROW(sine(4 * deg, 0), std::invalid_argument);
}

// Linear interpolation between the rows, the first / last angle outside the table; for a linear angle
// the centred difference is the exact slope, also next to the ends where the window is clipped.
TEST(TankMotion, TableInterpolatesAndHoldsOutside) {
  const TankMotion m(table_params({0.0, 1.0, 2.0, 4.0}, {0.0, 0.1, 0.3, 0.7}));
  EXPECT_DOUBLE_EQ(m.angle(0.0), 0.0);
  EXPECT_DOUBLE_EQ(m.angle(1.0), 0.1);
  EXPECT_DOUBLE_EQ(m.angle(0.5), 0.05);
  EXPECT_DOUBLE_EQ(m.angle(1.5), 0.2);
  EXPECT_DOUBLE_EQ(m.angle(3.0), 0.5);
  EXPECT_DOUBLE_EQ(m.angle(-1.0), 0.0);
  EXPECT_DOUBLE_EQ(m.angle(5.0), 0.7);
  EXPECT_DOUBLE_EQ(m.end_time(), 4.0);
  EXPECT_NEAR(m.angular_velocity(0.5), 0.1, 1e-14);
  EXPECT_NEAR(m.angular_velocity(0.01), 0.1, 1e-14);  // window clipped at the start
  EXPECT_NEAR(m.angular_velocity(3.0), 0.2, 1e-14);
  EXPECT_NEAR(m.angular_velocity(3.99), 0.2, 1e-14);  // clipped at the end
  // Across a kink: the mean slope over [t - h, t + h] (h = 0.025 s).
  EXPECT_NEAR(m.angular_velocity(1.0), 0.15, 1e-14);
  EXPECT_NEAR(m.angular_velocity(1.0125), (0.75 * 0.2 + 0.25 * 0.1), 1e-14);
  EXPECT_EQ(m.angular_velocity(-0.1), 0);  // the tank rests before and after the table
  EXPECT_EQ(m.angular_velocity(4.1), 0);
}

TEST(TankMotion, TableRejectsBadInput) {
  EXPECT_THROW(TankMotion(table_params({0.0}, {0.0})), std::invalid_argument);
  EXPECT_THROW(TankMotion(table_params({0.0, 1.0}, {0.0})), std::invalid_argument);
  EXPECT_THROW(TankMotion(table_params({0.0, 1.0, 1.0}, {0.0, 0.1, 0.2})), std::invalid_argument);
  TankMotionParams q = table_params({0.0, 1.0}, {0.0, 0.1});
  q.derivative_half_window = 0;
  EXPECT_THROW(TankMotion{q}, std::invalid_argument);
}

// A sine sampled every 0.01 s with +-0.01 deg of alternating noise (the measured deep series scatters by
// 0.009 deg rms about its 5-point running mean): the centred difference over 0.05 s recovers omega within
// 3 % of its amplitude (noise 0.02 deg / 0.05 s, plus 0.3 % attenuation of the box filter), while the
// slope of the single interval (the old piecewise-constant omega) is off by 2 deg/s, over 8 %.
TEST(TankMotion, TableAngularVelocityIsSmoothed) {
  const Real a = 4 * deg, period = 1.211, w = 2 * pi / period;
  std::vector<Real> t, th;
  for (int k = 0; k <= 500; ++k) {
    t.push_back(0.01 * k);
    th.push_back(a * std::sin(w * t.back()) + (k % 2 ? 0.01 : -0.01) * deg);
  }
  const TankMotion m(table_params(t, th));
  Real err = 0, err_raw = 0;
  for (Real s = 0.1; s < 4.9; s += 0.0037) {
    err = std::max(err, std::abs(m.angular_velocity(s) - a * w * std::cos(w * s)));
    const auto k = static_cast<std::size_t>(s / 0.01);
    err_raw = std::max(err_raw, std::abs((th[k + 1] - th[k]) / 0.01 - a * w * std::cos(w * s)));
  }
  std::printf("omega amplitude %.4f rad/s; max error: centred 0.05 s %.4f, one interval %.4f\n", a * w, err, err_raw);
  EXPECT_LT(err, 0.03 * a * w);
  EXPECT_GT(err_raw, 0.08 * a * w);
}

TEST(TankMotion, ReadsAngleTableInDegreesSkippingComments) {
  const TempFile f("# source line\ntime,angle\n0.0, 0.0\n0.5, 2.0\n1.0  -4.0\n\n");
  TankMotionParams q;
  q.type = TankMotionParams::Type::table;
  read_angle_table(f.path.string(), q);
  ASSERT_EQ(q.time.size(), 3u);
  EXPECT_DOUBLE_EQ(q.time[1], 0.5);
  EXPECT_NEAR(q.angle[1], 2 * deg, 1e-15);
  EXPECT_NEAR(q.angle[2], -4 * deg, 1e-15);
  const TankMotion m(q);
  EXPECT_NEAR(m.angle(0.75), -1 * deg, 1e-15);

  TankMotionParams r;
  EXPECT_THROW(read_angle_table("/nonexistent/roll.csv", r), std::runtime_error);
  const TempFile one("0.0, 1.0\n", "one.csv");
  EXPECT_THROW(read_angle_table(one.path.string(), r), std::runtime_error);
  const TempFile back("0.0, 1.0\n0.2, 1.0\n0.1, 1.0\n", "back.csv");
  EXPECT_THROW(read_angle_table(back.path.string(), r), std::runtime_error);
}

// The shipped measured series (cases/sloshing/): about +-4 deg with T ~ 1.21 s (deep) and +-2 deg with
// T ~ 1.67 s (hanging); the smoothed omega peaks near 2 pi A / T.
TEST(TankMotion, ShippedMeasuredSeries) {
  const std::string dir = std::string(MPSFSI_TEST_DATA_DIR) + "/../../cases/sloshing/";
  struct Expect {
    const char* file;
    Real amplitude_deg, period;
  };
  for (const Expect e : {Expect{"idelsohn2008_roll_RollingTankDeepTimeSeries.csv", 4.0, 1.21},
                         Expect{"idelsohn2008_roll_RollingTankHangingTimeSeries.csv", 2.0, 1.67}}) {
    TankMotionParams q;
    q.type = TankMotionParams::Type::table;
    read_angle_table(dir + e.file, q);
    const TankMotion m(q);
    Real a_max = 0, w_max = 0;
    for (Real t = 0; t < m.end_time(); t += 0.001) {
      a_max = std::max(a_max, std::abs(m.angle(t)));
      w_max = std::max(w_max, std::abs(m.angular_velocity(t)));
    }
    const Real w_ref = 2 * pi * e.amplitude_deg * deg / e.period;
    std::printf("%s: end %.3f s, max |angle| %.3f deg, max |omega| %.4f rad/s (2 pi A / T = %.4f)\n", e.file,
                m.end_time(), a_max / deg, w_max, w_ref);
    EXPECT_NEAR(a_max / deg, e.amplitude_deg, 0.05 * e.amplitude_deg) << e.file;
    EXPECT_NEAR(w_max, w_ref, 0.08 * w_ref) << e.file;
    EXPECT_GT(m.end_time(), 4.9);
  }
}

TEST(TankMotion, RigidRotationAboutThePivot) {
  const TankMotion m = sine(4 * deg, 1.2, Vec(0.3, 0.0));
  const Real q = pi / 2;
  const Vec x = m.place(Vec(0.4, 0.0), q);  // a quarter turn counter-clockwise
  EXPECT_NEAR(x[0], 0.3, 1e-15);
  EXPECT_NEAR(x[1], 0.1, 1e-15);
  const Vec v = m.velocity_at(Vec(0.4, 0.0), 2.0);  // omega x r, r = (0.1, 0)
  EXPECT_NEAR(v[0], 0.0, 1e-15);
  EXPECT_NEAR(v[1], 0.2, 1e-15);
  const Vec x0(0.15, 0.08);
  const Real th = 0.07;
  const Vec back = m.to_tank_frame(m.place(x0, th), th);
  EXPECT_NEAR((back - (x0 - m.pivot())).norm(), 0, 1e-15);
  // velocity_at is the time derivative of place
  const Real h = 1e-7;
  const Vec dx = (m.place(x0, th + h) - m.place(x0, th - h)) / (2 * h);
  EXPECT_NEAR((dx - m.velocity_at(m.place(x0, th), 1.0)).norm(), 0, 1e-8);
}

// Clamped solid particles follow the tank: position pivot + R(theta)(x0 - pivot), velocity omega x r,
// rotation theta; the tank-frame probe on a clamped particle reads zero, the global one does not.
TEST(TankMotion, ClampedSolidFollowsTankAndTankFrameProbeReadsZero) {
  CaseSpec spec = test::base_case(0.002, 1);
  spec.solid_materials.push_back(test::material("rubber", 1100, 6e6, 0.49));
  spec.solid.plane_stress = true;
  BodySpec plate = test::solid_body("plate", "rubber", Vec(0.298, -0.008), Vec(0.302, 0.06));
  plate.clamp = Rect{Vec(0.29, -0.01), Vec(0.31, 0.0)};
  spec.bodies.push_back(plate);
  spec.tank_motion.type = TankMotionType::sine_roll;
  spec.tank_motion.pivot = Vec(0.3, 0);
  spec.tank_motion.amplitude = 4 * deg;
  spec.tank_motion.period = 1.2;
  ProbeSpec root;
  root.name = "root";
  root.type = ProbeType::displacement;
  root.body = "plate";
  root.position = Vec(0.299, -0.003);
  root.frame = ProbeFrame::tank;
  ProbeSpec global = root;
  global.name = "root_global";
  global.frame = ProbeFrame::global;
  spec.probes = {root, global};

  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  std::vector<Vec> x0 = p.position;
  SolidSolver solid(solid_setup(spec), p);
  const ProbeWriter probes(spec, p, (fs::temp_directory_path() / "mpsfsi_tank_motion_probes.csv").string());
  const TankMotion tank = sine(4 * deg, 1.2, Vec(0.3, 0));
  const Real dt = solid.stable_dt();
  Real t = 0;
  while (t < 0.3) {  // to the largest roll
    solid.advance(t, dt);
    t += dt;
  }
  const auto [theta, omega] = tank.at(t);
  std::size_t n_clamped = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!p.clamped[i]) continue;
    ++n_clamped;
    EXPECT_NEAR((p.position[i] - tank.place(x0[i], theta)).norm(), 0, 1e-14);
    EXPECT_NEAR((p.velocity[i] - tank.velocity_at(p.position[i], omega)).norm(), 0, 1e-14);
    EXPECT_NEAR(p.scalar_field("rotation")[i], theta, 1e-15);
    EXPECT_NEAR(p.scalar_field("angular_velocity")[i], omega, 1e-15);
  }
  EXPECT_GT(n_clamped, 0u);
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_TRUE(p.position[i].allFinite());
  const std::vector<Real> v = probes.evaluate(p, t);
  ASSERT_EQ(v.size(), 4u);
  EXPECT_NEAR(v[0], 0, 1e-14);
  EXPECT_NEAR(v[1], 0, 1e-14);
  // Global: the root point turned through theta about the pivot.
  const Vec d = tank.place(Vec(0.299, -0.003), theta) - Vec(0.299, -0.003);  // a lattice point at dp 2 mm
  EXPECT_NEAR(v[2], d[0], 1e-12);
  EXPECT_NEAR(v[3], d[1], 1e-12);
  EXPECT_GT(std::abs(v[2]), 1e-4);
  fs::remove(fs::temp_directory_path() / "mpsfsi_tank_motion_probes.csv");
}
