#pragma once

#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace mrslam::common {

// The scenario schema as the parser knows it: the full path of every leaf key the parser looks
// up while parsing the given documents (sequence elements written "[]", e.g.
// "robots[].control.segments[].v_mps"). The parser looks up every key of each mapping it reads,
// present or not, so documents that hold each kind of section yield the whole schema. Throws
// ScenarioError as CreateScenarioOptions does. Not for concurrent use with itself.
std::set<std::string> ScenarioKeys(const std::vector<YAML::Node>& documents);

}  // namespace mrslam::common
