// Acceleration of the fixed-point iterations of an implicit (strong) partitioned coupling, in the manner of
// preCICE's accelerations. One time window is iterated: the coupled step, run with the interface data x_k
// (this rank's entries), gives H(x_k); the acceleration turns x_k and H(x_k) into the next input x_{k+1}. The
// residual is r_k = H(x_k) - x_k, and the window has converged when r_k is small (relative_residual).
//   constant  x_{k+1} = x_k + omega r_k.
//   aitken    the same with omega_k = -omega_{k-1} r_{k-1} . (r_k - r_{k-1}) / |r_k - r_{k-1}|^2 (Kuttler & Wall
//             2008, eq. 44); the first iteration of a window takes sign(omega) min(relaxation, |omega|) of the
//             last window's factor.
//   iqn-ils   interface quasi-Newton with an inverse Jacobian from least squares (Degroote, Bathe & Vierendeels
//             2009, eq. 19-22): V holds the differences of successive residuals, W those of successive outputs
//             H(x); c minimises |V c + r_k|, and x_{k+1} = H(x_k) + W c. The columns of the last `reuse` windows
//             are kept (preCICE's reused time windows); a column whose part orthogonal to the newer columns is
//             below `filter` times its norm is left out of the least squares (the QR2 filter of Haelterman et
//             al. 2016). With no column (the first iteration of the first window) it relaxes by omega.
// Dot products are reduced over the ranks of the communicator, so every rank takes the same factors. The
// entries are named by global id (each id `width` values, e.g. a displacement's components): the columns of
// past windows are kept only while the ids of every rank are the ones they were built with (particles that
// move to another rank or a surface that changes start the history afresh).
#pragma once

#include "core/types.hpp"
#include "coupling/coupling_parameters.hpp"

#include <mpi.h>

#include <Eigen/Core>

#include <deque>
#include <memory>
#include <string>
#include <vector>

namespace mpsfsi {

class BinaryWriter;
class BinaryReader;

/// Interface data: this rank's entries, `width` values per interface id.
using DataVector = Eigen::VectorXd;

/// |H(x) - x| / |H(x)| over all ranks (0 when both are zero); `floor` bounds the denominator from below, so
/// that a vanishing interface quantity is measured against a scale of the case's. A collective.
Real relative_residual(const DataVector& x, const DataVector& hx, Real floor, MPI_Comm comm);

/// The dot product of two distributed vectors (this rank's parts), summed over the ranks. A collective.
Real global_dot(const DataVector& a, const DataVector& b, MPI_Comm comm);

class Acceleration {
 public:
  virtual ~Acceleration() = default;

  /// One iteration of the current window: `ids` the global ids of this rank's entries (each `width`
  /// consecutive values of x), the same through the window; `x` the input the coupled step ran with and `hx`
  /// its output. Returns the next input. A collective.
  virtual DataVector next(const std::vector<GlobalId>& ids, const DataVector& x, const DataVector& hx) = 0;

  /// The window's iterations ended (converged, or stopped at the iteration limit): the next call of next()
  /// starts a new window.
  virtual void end_window() = 0;

  /// Iterations of the current window so far (calls of next() since the last end_window()).
  int iteration() const { return iteration_; }

  /// The name used in the case file (constant, aitken, iqn-ils).
  virtual std::string name() const = 0;

  /// Checkpoints, between windows: what the acceleration carries from one window to the next (Aitken's factor,
  /// IQN-ILS's kept columns by interface id). save_state is a collective: every rank's columns go into `out`
  /// on every rank. load_state keeps the rows of `ids`, this rank's interface now (any partition); columns it
  /// cannot map (an id the checkpoint lacks) are dropped.
  virtual void save_state(BinaryWriter& out) const;
  virtual void load_state(BinaryReader& in, const std::vector<GlobalId>& ids);

 protected:
  int iteration_ = 0;
};

/// The acceleration the parameters name, on communicator `comm` (which must outlive it). Throws
/// std::invalid_argument for parameters out of range (the case parser checks them first).
std::unique_ptr<Acceleration> make_acceleration(const AccelerationParameters& parameters, int width, MPI_Comm comm);

/// Interface quasi-Newton, least-squares inverse Jacobian (see the file's head). Public for its tests' use
/// of columns() and reused_columns().
class IqnIlsAcceleration : public Acceleration {
 public:
  IqnIlsAcceleration(const AccelerationParameters& parameters, int width, MPI_Comm comm);

  DataVector next(const std::vector<GlobalId>& ids, const DataVector& x, const DataVector& hx) override;
  void end_window() override;
  std::string name() const override { return "iqn-ils"; }
  void save_state(BinaryWriter& out) const override;
  void load_state(BinaryReader& in, const std::vector<GlobalId>& ids) override;

  /// Columns the least squares may use now (this window's and the kept ones of past windows), before filtering.
  int columns() const;
  /// Columns of past windows dropped because the interface's ids changed, since the start.
  long dropped_by_ids() const { return dropped_by_ids_; }
  /// Columns left out of the last least squares by the filter.
  int filtered() const { return filtered_; }

 private:
  /// One window's difference columns, newest first.
  struct Window {
    std::vector<DataVector> v;  ///< r_{k+1} - r_k
    std::vector<DataVector> w;  ///< H(x_{k+1}) - H(x_k)
  };
  /// Drops the kept columns when the ids differ from the ones they were built with on any rank.
  void check_ids(const std::vector<GlobalId>& ids);
  /// c minimising |V c + r| over the columns the filter keeps (newest first), and the matching W c.
  DataVector quasi_newton_update(const DataVector& r);

  AccelerationParameters parameters_;
  int width_ = 1;
  MPI_Comm comm_;
  Window current_;
  std::deque<Window> past_;  ///< the kept windows, newest first
  std::vector<GlobalId> ids_;
  DataVector last_r_, last_hx_;
  long dropped_by_ids_ = 0;
  int filtered_ = 0;
};

}  // namespace mpsfsi
