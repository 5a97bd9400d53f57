#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "robot_agent/filters/odometry_calibration.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/keyframe_graph.h"
#include "robot_agent/smoother/mover_memory.h"
#include "robot_agent/smoother/peer_landmarks.h"

namespace mrslam::robot_agent::smoother {

// filter.type smoother (docs/smoother.md): the maximum a posteriori estimate of the robot's
// recent path, its static landmarks and its odometry calibration (KeyframeGraph), with a
// FastSLAM front end of filter.smoother.front_end_particles particles that
// * labels every reading with a track (its most probable particle's association), so a wrong
//   association is a wrong label that the graph's Huber loss and gate bound and that is
//   re-decided at every solve;
// * tells static landmarks from moving ones: a track enters the graph once the front end maps it
//   as confirmed and static; a moving track is reported from the front end, re-anchored on the
//   graph's pose (its position relative to the front end's pose, placed relative to the graph's);
// * receives peers' moving landmarks (MergeLandmarks; those of known kinematics), which inform its
//   association. Peers' static landmarks are held apart (PeerLandmarks) and shown in the map
//   where the own map has nothing, without entering the estimate.
// A keyframe is made at every step with landmark readings and at least every
// max_keyframe_gap_steps steps. Each step reports the newest pose with its marginal covariance
// (the correction's uncertainty included) and the landmarks with theirs.
// Lost: when lost_after_keyframes keyframes in a row each have at least min_recovery_readings
// readings of which at most half fit the map (within the gate at the solution), the newest
// keyframe's pose is searched again: every pair of its readings is paired with every pair of
// mapped static landmarks at a consistent distance, the pose that explains both is scored by
// how many readings fall within the gate of some mapped landmark, and the best (more than half of
// the readings, and more than at the current pose) is taken: the keyframes since the trouble
// began are moved by it, the odometry factor into the first of them is cut (the robot moved in a
// way its odometry did not see), their readings are relabelled by the pose's associations, and
// the front end is reseated there. Not found, the search is made again at each further suspect
// keyframe, up to lost_after_keyframes more, before the landmarks held out are let in.
class OnlineSmoother : public filters::SlamFilter {
 public:
  OnlineSmoother(const AgentOptions& options, std::uint64_t seed);

  void Process(const common::SensorStep& step) override;
  filters::FilterEstimate Estimate() const override;
  // The front end's state, the calibration, the graph and the bookkeeping of lost keyframes.
  void Io(common::Archive& ar) override;
  // The object, the front end's state (its FastSLAM particles and maps) and its last estimate,
  // and the graph's (KeyframeGraph::EstimatorBytes): grows by one keyframe's bytes for each
  // keyframe marginalized into the fixed history.
  std::size_t EstimatorBytes() const override;
  // The graph's relinearization, when due (KeyframeGraph::Settle).
  void Settle() override { graph_.Settle(); }
  int MergeLandmarks(const std::vector<filters::MapLandmark>& landmarks_in_own_frame, MapFusionRule rule,
                     double gate_probability, double too_close_m) override;

  // Every keyframe's pose, all the run's data solved at once (KeyframeGraph::SmoothAll).
  std::vector<std::pair<int, common::Pose2>> FinalTrajectory() const override { return graph_.SmoothAll(); }

  const KeyframeGraph& Graph() const { return graph_; }
  // Times the pose was searched again and a better one found.
  int Recoveries() const { return recoveries_; }
  // The front end's tracks joined to the graph's chain of a mover it had lost (JoinRemapped).
  const std::map<std::uint32_t, std::uint32_t>& Joined() const { return joined_; }

 private:
  std::vector<KeyframeGraph::Reading> LabelledReadings(const common::SensorStep& step,
                                                       const filters::FilterEstimate& front) const;
  void UpdateTracks(const filters::FilterEstimate& front, const std::vector<KeyframeGraph::Reading>& readings);
  // Among known candidate kinematics, each mover's (v, w): the front end's candidate until the
  // graph's chain of it has kMinChoiceStates states; then, at every keyframe while the chain is
  // younger than the window, the candidate whose KeyframeGraph::TrialCost is lowest, the one held
  // unless another's is lower by more than kKinematicsSwitchMargin (odds of 100 to 1, 2 ln 100:
  // no flapping between candidates the evidence cannot tell apart); then held. The front end's
  // particles settle on one candidate within a few steps and rarely come back from a wrong one.
  static constexpr int kMinChoiceStates = 3;
  static constexpr double kKinematicsSwitchMargin = 9.21;
  void ChooseKinematics(std::map<std::uint32_t, KeyframeGraph::MoverModel>* movers);
  // Among known candidate kinematics, a graph's chain goes on while the front end does not report
  // its track as a mover for a while (not confirmed, heading unknown, or dropped) without naming
  // it static: dropped, the chain's history would be lost, and a chain started again has no
  // heading to predict by. (With estimated motion a kept chain's model would extrapolate a mover
  // that turns: there the front end decides.)
  void KeepChains(const std::set<std::uint32_t>& fixed,
                  std::map<std::uint32_t, KeyframeGraph::MoverModel>* movers) const;
  // Among known candidate kinematics, a mover the front end lost and mapped again under a new
  // track continues the graph's chain of the old one: a moving track without a chain, first
  // mapped after the newest state of a chain not read now, whose position (re-anchored on the
  // graph's pose by `shift`) lies within the chi-square gate of cooperation.match_gate_probability
  // of that chain's prediction (the sum of both covariances), and whose nearest candidate is the
  // chain's, is joined to the nearest such chain: its model goes to that chain's track, and its
  // readings are labelled with it from then on (joined_). With known kinematics the prediction
  // across the gap is as good as the model, and the motion link keeps what the chain knew.
  void JoinRemapped(const filters::FilterEstimate& front, const common::Pose2& shift,
                    const std::vector<KeyframeGraph::Reading>& readings,
                    std::map<std::uint32_t, KeyframeGraph::MoverModel>* movers);
  filters::MapLandmark FrontLandmark(std::uint32_t track) const;
  std::vector<filters::MapLandmark> GraphLandmarks(int step) const;
  std::vector<filters::MapLandmark> OwnLandmarks(int step) const;
  // Process but for the movers' memory.
  void Advance(const common::SensorStep& step);
  // Whether movers out of sight are shown by MoverMemory (filter.smoother.mover_memory_s, among
  // movers of unknown kinematics).
  bool RemembersMovers() const;
  // How well pose x explains the newest keyframe's readings by the static map: readings within
  // the gate of a mapped landmark (with the landmark each is relabelled to), mapped landmarks
  // well inside the view (within 0.9 of the range, 0.45 of the field of view) and how many of
  // those a reading explains.
  struct Support {
    int fit = 0, in_view = 0, seen = 0;
    std::map<std::uint32_t, std::uint32_t> labels;
  };
  Support Explain(const common::Pose2& x) const;
  void CheckLost(int step);
  // PeerLandmarks::CountMisses for the step's scan.
  void CountPeerMisses(const common::SensorStep& step);
  bool Recover(const Support& now);

  AgentOptions options_;
  std::unique_ptr<filters::SlamFilter> front_end_;
  filters::OdometryCalibration calibration_;
  KeyframeGraph graph_;
  filters::FilterEstimate front_;  // the front end's estimate of the last step
  int step_ = 0;
  int since_keyframe_ = 0;
  int lost_keyframes_ = 0;
  int lost_since_step_ = -1;  // the first keyframe of the current run of misfits
  int recoveries_ = 0;
  PeerLandmarks peers_;
  MoverMemory movers_;
  std::map<std::uint32_t, int> kinematics_;        // per moving track: the candidate the graph uses
  std::map<std::uint32_t, std::uint32_t> joined_;  // a front end's track -> the graph's chain it continues
};

}  // namespace mrslam::robot_agent::smoother
