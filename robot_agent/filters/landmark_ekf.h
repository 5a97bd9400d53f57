#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <Eigen/Core>

#include "common/angles.h"
#include "common/se2.h"

// The per-landmark EKF of the particle filter: its motion models, its range-bearing measurement
// model, and the kernels that run them over many landmarks at once.
//
// State of one landmark, by kinematic model (D = state dimension):
//   static             D = 2: (x, y)
//   unicycle, known v,w D = 3: (x, y, heading); (v, w) are parameters of the landmark
//   constant turn rate D = 5: (x, y, heading, v, w), v and w estimated online
// Motion (docs/models.md): heading' = heading + w dt; x' = x + v dt cos(heading');
//                     y' = y + v dt sin(heading'); v' = v; w' = w; plus N(0, Q) per step.
// Measurement from a robot pose (xr, yr, phi):
//   r = sqrt(dx^2 + dy^2),  b = atan2(dy, dx) - phi,  dx = x - xr, dy = y - yr.
//   H_m = d(r, b)/d(x, y) = [[dx/r, dy/r], [-dy/q, dx/q]]  (q = r^2; zero for the other states)
//   H_x = d(r, b)/d(xr, yr, phi) = [-H_m | (0, -1)^T]
//
// Storage is structure-of-arrays: a LandmarkBlock holds kLanes landmarks field by field, so
// the kernels below run two, four or eight landmarks per instruction (SSE2, AVX2 or AVX-512F,
// the widest the CPU has, chosen at run time). The maths is written once, generic over the lane
// type T (double for one landmark, Double2/4/8 for more), so that the tests check the
// scalar instantiation against Eigen and numeric differences and the filter runs the same code.
namespace mrslam::robot_agent::filters {

// The lane maths below is small and hot: always inlined into the kernels. Its loops over the
// state's entries and the lanes are unrolled (#pragma GCC unroll): GCC's generic tuning leaves
// some of them rolled, which keeps their arrays in memory; unrolled, the AVX2 kernel over
// contiguous rows went from 46 to 83 M/s here.
#define MRSLAM_LANE_INLINE inline __attribute__((always_inline))

// Two doubles in one SSE2 register (GCC/Clang vector extension) and its comparison mask.
using Double2 = double __attribute__((vector_size(16)));
using Mask2 = long __attribute__((vector_size(16)));  // NOLINT(runtime/int): the mask type

inline double Select(bool c, double a, double b) { return c ? a : b; }
inline Double2 Select(Mask2 c, Double2 a, Double2 b) { return c ? a : b; }
inline double Sqrt(double x) { return std::sqrt(x); }
inline Double2 Sqrt(Double2 x) {
#if defined(__x86_64__)
  return _mm_sqrt_pd(x);
#else
  return Double2{std::sqrt(x[0]), std::sqrt(x[1])};
#endif
}
inline double Abs(double x) { return std::abs(x); }
inline Double2 Abs(Double2 x) { return Select(x < 0.0, -x, x); }
inline double Max(double a, double b) { return a > b ? a : b; }
inline Double2 Max(Double2 a, Double2 b) { return Select(a > b, a, b); }
inline double Min(double a, double b) { return a < b ? a : b; }
inline Double2 Min(Double2 a, Double2 b) { return Select(a < b, a, b); }
// The lane maths is always inlined into its kernels (the Double4 ones compiled for AVX2), so no
// call with a vector argument ever crosses the ABI that -Wpsabi warns about.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

#if defined(__x86_64__)
// Four doubles in one AVX register: used only inside functions compiled for AVX2 (chosen at run
// time when the CPU has it); same IEEE operations, so the same numbers as two Double2.
using Double4 = double __attribute__((vector_size(32)));
using Mask4 = long __attribute__((vector_size(32)));  // NOLINT(runtime/int): the mask type
MRSLAM_LANE_INLINE Double4 Select(Mask4 c, Double4 a, Double4 b) { return c ? a : b; }
// One vsqrtpd per vector, written by hand: the intrinsic needs a caller compiled for AVX, and the
// generic lane maths between it and the kernel is not. Clang checks the register's width where
// the asm stands, so there (and for clang-tidy) the square roots are SSE2 ones, two per Double4.
MRSLAM_LANE_INLINE Double4 Sqrt(Double4 x) {
#if defined(__clang__)
  const Double2 lo = _mm_sqrt_pd(Double2{x[0], x[1]}), hi = _mm_sqrt_pd(Double2{x[2], x[3]});
  return Double4{lo[0], lo[1], hi[0], hi[1]};
#else
  Double4 r;
  asm("vsqrtpd %1, %0" : "=x"(r) : "x"(x));
  return r;
#endif
}
MRSLAM_LANE_INLINE Double4 Abs(Double4 x) { return Select(x < 0.0, -x, x); }
MRSLAM_LANE_INLINE Double4 Max(Double4 a, Double4 b) { return Select(a > b, a, b); }
MRSLAM_LANE_INLINE Double4 Min(Double4 a, Double4 b) { return Select(a < b, a, b); }
// Eight doubles in one AVX-512 register, likewise only inside functions compiled for AVX-512F.
using Double8 = double __attribute__((vector_size(64)));
using Mask8 = long __attribute__((vector_size(64)));  // NOLINT(runtime/int): the mask type
MRSLAM_LANE_INLINE Double8 Select(Mask8 c, Double8 a, Double8 b) { return c ? a : b; }
MRSLAM_LANE_INLINE Double8 Sqrt(Double8 x) {  // likewise
#if defined(__clang__)
  const Double4 lo = Sqrt(Double4{x[0], x[1], x[2], x[3]}), hi = Sqrt(Double4{x[4], x[5], x[6], x[7]});
  return Double8{lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]};
#else
  Double8 r;
  asm("vsqrtpd %1, %0" : "=v"(r) : "v"(x));
  return r;
#endif
}
MRSLAM_LANE_INLINE Double8 Abs(Double8 x) { return Select(x < 0.0, -x, x); }
MRSLAM_LANE_INLINE Double8 Max(Double8 a, Double8 b) { return Select(a > b, a, b); }
MRSLAM_LANE_INLINE Double8 Min(Double8 a, Double8 b) { return Select(a < b, a, b); }
#endif
template <typename T>
T Splat(double x) {
  return T{} + x;
}

// atan2(y, x) without a library call, accurate to a few ulp (Cephes' atan: reduce the ratio
// t = min(|x|, |y|) / max(|x|, |y|) to |t| <= 0.66 with atan(t) = pi/4 + atan((t - 1) / (t + 1)),
// then atan(t) = t + t z P(z) / Q(z), z = t^2; fold back by octant and quadrant).
template <typename T>
MRSLAM_LANE_INLINE T Atan2(T y, T x) {
  constexpr double kP[5] = {-8.750608600031904122785e-1, -1.615753718733365076637e1, -7.500855792314704667340e1,
                            -1.228866684490136173410e2, -6.485021904942025371773e1};
  constexpr double kQ[5] = {2.485846490142306297962e1, 1.650270098316988542046e2, 4.328810604912902668951e2,
                            4.853903996359136964868e2, 1.945506571482613964425e2};
  constexpr double kMoreBits = 6.123233995736765886130e-17;
  const T ax = Abs(x), ay = Abs(y);
  const T hi = Max(ax, ay), lo = Min(ax, ay);
  // t = lo / hi > 0.66  <=>  lo > 0.66 hi; then (t - 1) / (t + 1) = (lo - hi) / (lo + hi).
  const auto big = lo > 0.66 * hi;
  const T tr = Select(big, lo - hi, lo) / Max(Select(big, lo + hi, hi), Splat<T>(1e-300));
  const T z = tr * tr;
  const T p = (((kP[0] * z + kP[1]) * z + kP[2]) * z + kP[3]) * z + kP[4];
  const T q = ((((z + kQ[0]) * z + kQ[1]) * z + kQ[2]) * z + kQ[3]) * z + kQ[4];
  T a = tr + tr * z * p / q;
  a = Select(big, a + (0.25 * common::kPi + 0.5 * kMoreBits), a);
  a = Select(ay > ax, (0.5 * common::kPi + kMoreBits) - a, a);
  a = Select(x < 0.0, common::kPi - a, a);
  return Select(y < 0.0, -a, a);
}

// Wraps an angle in (-3 pi, 3 pi] to (-pi, pi] (branch-free for lanes).
template <typename T>
MRSLAM_LANE_INLINE T WrapNear(T a) {
  a = Select(a > common::kPi, a - 2.0 * common::kPi, a);
  return Select(a <= -common::kPi, a + 2.0 * common::kPi, a);
}

// Number of entries in the upper triangle of a D x D covariance, and the index of (i, j) in it
// (row-major upper triangle).
constexpr int TriangleSize(int d) { return d * (d + 1) / 2; }
constexpr int Tri(int i, int j, int d) { return i <= j ? i * d - i * (i - 1) / 2 + (j - i) : Tri(j, i, d); }

// The predicted range-bearing measurement of point (lx, ly) from pose (xr, yr, phi), its
// innovation against (z_r, z_b) and the Jacobian H_m (a) of (r, b) with respect to the point.
template <typename T>
struct RangeBearingModel {
  T nu_r, nu_b;          // innovation z - h, bearing wrapped
  T a00, a01, a10, a11;  // H_m
};
template <typename T>
MRSLAM_LANE_INLINE RangeBearingModel<T> PredictMeasurement(T lx, T ly, T xr, T yr, T phi, T z_r, T z_b) {
  const T dx = lx - xr, dy = ly - yr;
  const T q = Max(dx * dx + dy * dy, Splat<T>(1e-12));
  const T r = Sqrt(q);
  const T inv_q = 1.0 / q;
  const T inv_r = r * inv_q;
  // nu_b = wrap(z_b - (atan2(dy, dx) - phi)); every term is in (-pi, pi].
  const T nu_b = WrapNear(WrapNear(z_b + phi) - Atan2(dy, dx));
  return {z_r - r, nu_b, dx * inv_r, dy * inv_r, -dy * inv_q, dx * inv_q};
}

// The landmark EKF update with one range-bearing measurement z (noise variances var_r, var_b)
// from pose (xr, yr, phi), in place on mean[D] and the upper triangle cov[TriangleSize(D)]:
//   C = P H^T (D x 2; H = [H_m 0]), S = H_m P_pp H_m^T + R, K = C S^-1,
//   mean += K nu,  P -= K C^T.
template <typename T, int D>
MRSLAM_LANE_INLINE void EkfUpdate(T* mean, T* cov, T xr, T yr, T phi, T z_r, T z_b, double var_r, double var_b) {
  const RangeBearingModel<T> m = PredictMeasurement(mean[0], mean[1], xr, yr, phi, z_r, z_b);
  T c0[D], c1[D];  // columns of C = P H^T
#pragma GCC unroll 16
  for (int i = 0; i < D; ++i) {
    const T p0 = cov[Tri(i, 0, D)], p1 = cov[Tri(i, 1, D)];
    c0[i] = p0 * m.a00 + p1 * m.a01;
    c1[i] = p0 * m.a10 + p1 * m.a11;
  }
  const T s00 = m.a00 * c0[0] + m.a01 * c0[1] + var_r;
  const T s01 = m.a00 * c1[0] + m.a01 * c1[1];
  const T s11 = m.a10 * c1[0] + m.a11 * c1[1] + var_b;
  const T inv_det = 1.0 / (s00 * s11 - s01 * s01);
  const T i00 = s11 * inv_det, i01 = -s01 * inv_det, i11 = s00 * inv_det;
  T k0[D], k1[D];
#pragma GCC unroll 16
  for (int i = 0; i < D; ++i) {
    k0[i] = c0[i] * i00 + c1[i] * i01;
    k1[i] = c0[i] * i01 + c1[i] * i11;
    mean[i] = mean[i] + k0[i] * m.nu_r + k1[i] * m.nu_b;
  }
#pragma GCC unroll 16
  for (int i = 0; i < D; ++i) {
#pragma GCC unroll 16
    for (int j = i; j < D; ++j) cov[Tri(i, j, D)] = cov[Tri(i, j, D)] - (k0[i] * c0[j] + k1[i] * c1[j]);
  }
}

// The landmark EKF prediction over one step dt, in place. v, w are the known parameters for
// D = 3 (ignored otherwise); q[D] the process noise variances per step.
//   F = I + E with E nonzero only in rows 0..2, columns 2..D-1:
//     D = 3: E(0,2) = -v dt s, E(1,2) = v dt c            (c, s = cos, sin of heading')
//     D = 5: also E(0,3) = dt c, E(1,3) = dt s, E(0,4) = -v dt^2 s, E(1,4) = v dt^2 c, E(2,4) = dt
//   P' = F P F^T + Q = P + G + G^T + G E^T + Q,  G = E P.
template <typename T, int D>
MRSLAM_LANE_INLINE void EkfPredict(T* mean, T* cov, T v_param, T w_param, double dt, const double* q) {
  if constexpr (D == 2) {
    cov[Tri(0, 0, D)] = cov[Tri(0, 0, D)] + q[0];
    cov[Tri(1, 1, D)] = cov[Tri(1, 1, D)] + q[1];
    (void)mean;
    (void)v_param;
    (void)w_param;
    (void)dt;
  } else {
    const T v = D == 5 ? mean[3] : v_param;
    const T w = D == 5 ? mean[4] : w_param;
    const T heading = mean[2] + w * dt;
    T c, s;
    if constexpr (std::is_same_v<T, double>) {
      c = std::cos(heading);
      s = std::sin(heading);
    } else {
#pragma GCC unroll 16
      for (int l = 0; l < static_cast<int>(sizeof(T) / sizeof(double)); ++l) {
        c[l] = std::cos(heading[l]);
        s[l] = std::sin(heading[l]);
      }
    }
    constexpr int kRows = D == 5 ? 3 : 2;
    T e[3][D] = {};
    e[0][2] = -v * dt * s;
    e[1][2] = v * dt * c;
    if constexpr (D == 5) {
      e[0][3] = dt * c;
      e[1][3] = dt * s;
      e[0][4] = -v * dt * dt * s;
      e[1][4] = v * dt * dt * c;
      e[2][4] = Splat<T>(dt);
    }
    T g[3][D];  // G = E P, rows 0..kRows-1
#pragma GCC unroll 16
    for (int i = 0; i < kRows; ++i) {
#pragma GCC unroll 16
      for (int j = 0; j < D; ++j) {
        T acc = Splat<T>(0.0);
#pragma GCC unroll 16
        for (int k = 2; k < D; ++k) acc = acc + e[i][k] * cov[Tri(k, j, D)];
        g[i][j] = acc;
      }
    }
#pragma GCC unroll 16
    for (int i = 0; i < D; ++i) {
#pragma GCC unroll 16
      for (int j = i; j < D; ++j) {
        T add = Splat<T>(0.0);
        if (i < kRows) add = add + g[i][j];
        if (j < kRows) add = add + g[j][i];
        if (i < kRows && j < kRows) {
#pragma GCC unroll 16
          for (int k = 2; k < D; ++k) add = add + g[i][k] * e[j][k];
        }
        if (i == j) add = add + q[i];
        cov[Tri(i, j, D)] = cov[Tri(i, j, D)] + add;
      }
    }
    mean[0] = mean[0] + v * dt * c;
    mean[1] = mean[1] + v * dt * s;
    mean[2] = WrapNear(heading);
  }
}

#pragma GCC diagnostic pop

// Eigen forms of the models for one landmark (tests, initialization, reporting).
template <int D>
using StateVector = Eigen::Matrix<double, D, 1>;
template <int D>
using StateMatrix = Eigen::Matrix<double, D, D>;
// F = d(motion)/d(state) at mean (see EkfPredict).
template <int D>
StateMatrix<D> MotionJacobian(const StateVector<D>& mean, double v_param, double w_param, double dt);
// The motion model's mean: f(mean).
template <int D>
StateVector<D> MotionMean(const StateVector<D>& mean, double v_param, double w_param, double dt);
// H_m (2 x 2) and H_x (2 x 3) at a landmark position and a robot pose.
Eigen::Matrix2d MeasurementJacobianLandmark(const Eigen::Vector2d& landmark, const common::Pose2& pose);
Eigen::Matrix<double, 2, 3> MeasurementJacobianPose(const Eigen::Vector2d& landmark, const common::Pose2& pose);

// Bookkeeping of one landmark slot of one particle.
struct LandmarkMeta {
  std::uint32_t track_id = 0;      // shared by every particle that created it from one detection
  std::int32_t landmark_id = -1;   // reported identity, -1 if unknown
  std::uint32_t origin_track = 0;  // provenance (MapLandmark::origin_robot, origin_track)
  std::int16_t origin_robot = -1;
  std::uint32_t first_seen_step = 0;
  std::uint32_t last_seen_step = 0;
  std::uint16_t sightings = 0;
  std::uint16_t misses = 0;    // consecutive steps expected in view but not seen
  std::int8_t candidate = -1;  // known_candidates: index of the kinematics it follows
  bool position_only = false;  // seen once: position known, heading (and speed) not yet
  bool stationary = false;     // constant turn rate: this particle takes it as static
};

// kLanes landmarks of one particle, structure-of-arrays: field[f][lane]. Fields: mean[D], the
// upper triangle of the covariance, and for D = 3 the known (v, w) parameters. Shared between
// particles after resampling (copy-on-write through std::shared_ptr in the particle's map).
constexpr int kLanes = 8;
template <int D>
struct LandmarkBlock {
  static constexpr int kParams = D == 3 ? 2 : 0;
  static constexpr int kCov = D;                       // first covariance field
  static constexpr int kParamV = D + TriangleSize(D);  // D = 3 only
  static constexpr int kParamW = kParamV + 1;
  static constexpr int kFields = D + TriangleSize(D) + kParams;
  alignas(64) double field[kFields][kLanes] = {};
  LandmarkMeta meta[kLanes];

  double& Mean(int i, int lane) { return field[i][lane]; }
  double Mean(int i, int lane) const { return field[i][lane]; }
  double& Cov(int i, int j, int lane) { return field[kCov + Tri(i, j, D)][lane]; }
  double Cov(int i, int j, int lane) const { return field[kCov + Tri(i, j, D)][lane]; }
  StateVector<D> MeanVector(int lane) const;
  StateMatrix<D> CovMatrix(int lane) const;
  void Set(int lane, const StateVector<D>& mean, const StateMatrix<D>& cov);
  // Copies every field and the bookkeeping of one lane to a lane of another block.
  void CopyLane(int lane, LandmarkBlock* to, int to_lane) const;
};

// Asks the caches for every row of a block ahead of a pass that reads it. A particle's blocks
// are reached through pointers, which the hardware's prefetcher does not follow, and the blocks
// of all particles do not stay in cache from one pass to the next.
template <int D>
inline void PrefetchBlock(const LandmarkBlock<D>* block) {
  for (int f = 0; f < LandmarkBlock<D>::kFields; ++f) __builtin_prefetch(&block->field[f][0]);
  constexpr int kMetaPerLine = 64 / sizeof(LandmarkMeta);
  for (int l = 0; l < kLanes; l += kMetaPerLine) __builtin_prefetch(&block->meta[l]);
}

// Predicts the first `count` lanes of a block over one step (EkfPredict, several lanes at a time).
template <int D>
void PredictBlock(LandmarkBlock<D>* block, int count, double dt, const double* q);

// Squared Mahalanobis distance of measurement (z_r, z_b) to each of the first `count` lanes
// (d2[lane]; lanes beyond count are set to +inf) from pose (xr, yr, phi) whose own uncertainty
// is pose_cov (3 x 3, zero for a sampled pose):
//   S = H_m P_pp H_m^T + H_x Sigma H_x^T + R,  d2 = nu^T S^-1 nu.
// With Euclidean gating it is nu_r^2 + nu_b^2 instead (paper A's eq. 14).
template <int D>
void GateBlock(const LandmarkBlock<D>& block, int count, const common::Pose2& pose, const Eigen::Matrix3d& pose_cov,
               double z_r, double z_b, double var_r, double var_b, bool euclidean, double* d2);

// A batch of landmark EKF updates across particles: queues each (block, lane, pose, z), then
// runs EkfUpdate eight, four or two lanes at a time (AVX-512F, AVX2, SSE2). A block whose kLanes
// lanes are queued one after the other in lane order (a whole block) is updated as it lies: each
// of its fields is one contiguous row, loaded into vector registers and stored back as such, and
// its inputs are queued as rows of kLanes values beside it. The other updates (single lanes) load
// each lane's state from its block into a vector register lane by lane and store the result
// straight back. Both run the same EkfUpdate on each lane, so the numbers depend neither on the
// path nor on the vector width. The filter queues every update of a step here; the blocks must
// stay alive and not move until Run. A lane may be queued at most once per Run. Add runs the
// batch by itself when about kFlushSize updates are queued, which keeps the inputs in cache.
template <int D>
class UpdateBatch {
 public:
  static constexpr int kInputs = 5;  // xr, yr, phi, z_r, z_b
  // The inputs of one whole block, row i = input i of lanes 0..kLanes-1.
  struct alignas(64) WholeInputs {
    double row[kInputs][kLanes];
  };

  UpdateBatch(double var_r, double var_b);
  void Add(LandmarkBlock<D>* block, int lane, const common::Pose2& pose, double z_r, double z_b);
  void Run();
  int size() const { return size_ + kLanes * whole_size_ + open_lanes_; }

 private:
  static constexpr int kFlushSize = 1024;  // a multiple of 8: padding lanes fit in the stride
  static constexpr int kFlushBlocks = kFlushSize / kLanes;
  // Rows of kFlushSize values, one cache line apart beyond a multiple of 4 KiB so that the rows
  // do not all fall into one L1 set.
  static constexpr int kRowStride = kFlushSize + 8;
  double& Input(int i, int k) { return rows_[static_cast<std::size_t>(i) * kRowStride + k]; }
  void AddSingle(LandmarkBlock<D>* block, int lane, const common::Pose2& pose, double z_r, double z_b);
  // The open run (lanes 0..open_lanes_-1 of whole_[whole_size_], not yet a whole block) becomes
  // single updates.
  void SpillRun();

  double var_r_, var_b_;
  int size_ = 0;                           // single lanes queued
  std::vector<LandmarkBlock<D>*> blocks_;  // kFlushSize
  std::vector<int> lanes_;                 // kFlushSize
  std::vector<double> rows_;               // kInputs input rows
  int whole_size_ = 0;                     // whole blocks queued
  int open_lanes_ = 0;                     // lanes of the next whole block queued so far
  std::vector<LandmarkBlock<D>*> whole_;   // kFlushBlocks
  std::vector<WholeInputs> whole_inputs_;  // kFlushBlocks
};

template <int D>
inline void UpdateBatch<D>::AddSingle(LandmarkBlock<D>* block, int lane, const common::Pose2& pose, double z_r,
                                      double z_b) {
  const int k = size_++;
  blocks_[k] = block;
  lanes_[k] = lane;
  Input(0, k) = pose.x;
  Input(1, k) = pose.y;
  Input(2, k) = pose.heading;
  Input(3, k) = z_r;
  Input(4, k) = z_b;
}

template <int D>
inline void UpdateBatch<D>::Add(LandmarkBlock<D>* block, int lane, const common::Pose2& pose, double z_r, double z_b) {
  // Lane l of the block whose lanes 0..l-1 came just before continues the open run; lane 0 opens
  // one; anything else ends it.
  if (lane != open_lanes_ || (lane > 0 && block != whole_[whole_size_])) SpillRun();
  if (lane == open_lanes_) {
    whole_[whole_size_] = block;
    double(&row)[kInputs][kLanes] = whole_inputs_[whole_size_].row;
    row[0][lane] = pose.x;
    row[1][lane] = pose.y;
    row[2][lane] = pose.heading;
    row[3][lane] = z_r;
    row[4][lane] = z_b;
    if (++open_lanes_ == kLanes) {
      ++whole_size_;
      open_lanes_ = 0;
    }
  } else {
    AddSingle(block, lane, pose, z_r, z_b);
  }
  // Room for a spilled run and one more update.
  if (size_ > kFlushSize - kLanes || whole_size_ == kFlushBlocks) Run();
}

}  // namespace mrslam::robot_agent::filters
