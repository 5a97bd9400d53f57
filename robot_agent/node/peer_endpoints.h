#pragma once

#include <optional>
#include <string>
#include <vector>

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

// A step's peer messages in their DDS form, stamped with their sequence numbers, ready to write
// (each names its recipient).
struct PeerMessages {
  std::vector<msg::RelativeMeasurement> relative;
  std::vector<msg::MapSnapshot> maps;
  std::vector<msg::LandmarkMovedNotice> moved;
  std::vector<msg::FactorBatch> factors;
};

}  // namespace mrslam::robot_agent
