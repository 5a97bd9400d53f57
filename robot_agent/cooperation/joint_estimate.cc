#include "robot_agent/cooperation/joint_estimate.h"

#include <stdexcept>

namespace mrslam::robot_agent::cooperation {

std::vector<smoother::JointGraph::RobotLog> RobotLogs(const std::string& self,
                                                      const std::map<std::string, FactorLog>& logs) {
  const auto own = logs.find(self);
  if (own == logs.end()) throw std::invalid_argument("no log of the own robot " + self);
  std::vector<smoother::JointGraph::RobotLog> robots{{self, own->second.first_pose, &own->second.steps}};
  for (const auto& [origin, log] : logs) {
    if (origin != self) robots.push_back({origin, log.first_pose, &log.steps});
  }
  return robots;
}

JointEstimate Summarize(const smoother::JointGraph& graph, const std::vector<smoother::JointGraph::RobotLog>& robots) {
  JointEstimate out;
  out.path = graph.Path(0);
  for (int r = 1; r < graph.Robots(); ++r) {
    if (graph.Placed(r)) {
      out.frames.push_back({robots[r].id, graph.Frame(r), graph.FrameCovariance(r)});
    } else {
      out.not_placed.push_back(robots[r].id);
    }
  }
  out.readings = graph.Readings();
  out.outliers = graph.Outliers();
  return out;
}

JointEstimate SolveJoint(const AgentOptions& options, const std::string& self,
                         const std::map<std::string, FactorLog>& logs) {
  const auto robots = RobotLogs(self, logs);
  smoother::JointGraph graph(options, robots);
  graph.Solve();
  return Summarize(graph, robots);
}

}  // namespace mrslam::robot_agent::cooperation
