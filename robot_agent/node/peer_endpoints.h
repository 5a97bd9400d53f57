#pragma once

#include <optional>
#include <string>

#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"

// The agent's DDS endpoints toward one peer (docs/cooperation.md). Every peer message travels on
// its sender's own topic into its recipient, mrslam/peer/<recipient>/from/<sender>/<kind>, so
// that with DDS-Security the permissions bind the sender to the identity that wrote it.
namespace mrslam::robot_agent {

// Readers of what one peer sends to this agent (created at start-up for every peer of the team;
// the raw measurements' only when they are shared).
struct PeerReaders {
  PeerReaders(dds::Participant& participant, const std::string& self, const std::string& peer, dds::Notifier* notifier,
              bool share_factors);
  dds::Reader<msg::RelativeMeasurementPubSubType> relative;
  dds::Reader<msg::MapSnapshotPubSubType> map;
  dds::Reader<msg::LandmarkMovedNoticePubSubType> moved;
  std::optional<dds::Reader<msg::FactorBatchPubSubType>> factors;
};

// Writers of what this agent sends to one peer (created when it first sends to that peer; the raw
// measurements' only when they are shared).
struct PeerWriters {
  PeerWriters(dds::Participant& participant, const std::string& self, const std::string& peer, bool share_factors);
  dds::Writer<msg::RelativeMeasurementPubSubType> relative;
  dds::Writer<msg::MapSnapshotPubSubType> map;
  dds::Writer<msg::LandmarkMovedNoticePubSubType> moved;
  std::optional<dds::Writer<msg::FactorBatchPubSubType>> factors;
};

}  // namespace mrslam::robot_agent
