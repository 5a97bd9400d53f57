# Cooperation among robots: rendezvous maths (transform from mutual detections, chaining, split
# covariance intersection), map fusion rules and matching, the agents' protocol in process
# (rendezvous, snapshots, transitive frames), the rejection of hostile peer input and FastSLAM's
# merge of a peer's map.
mrslam_add_test(map_fusion_test
  SOURCES map_fusion_test.cc
  LIBS mrslam_agent_filters)
mrslam_add_test(rendezvous_test
  SOURCES rendezvous_test.cc
  LIBS mrslam_agent_cooperation)
mrslam_add_test(cooperation_test
  SOURCES cooperation_test.cc
  LIBS mrslam_agent_cooperation mrslam_agent_factory mrslam_config)
mrslam_add_test(peer_input_test
  SOURCES peer_input_test.cc
  LIBS mrslam_agent_cooperation mrslam_agent_factory mrslam_config)
mrslam_add_test(fastslam_merge_test
  SOURCES fastslam_merge_test.cc
  LIBS mrslam_agent_cooperation mrslam_agent_factory mrslam_config)
mrslam_add_test(joint_transform_test
  SOURCES joint_transform_test.cc
  LIBS mrslam_agent_cooperation mrslam_agent_factory mrslam_config mrslam_world_source)
mrslam_add_test(factor_exchange_test
  SOURCES factor_exchange_test.cc
  LIBS mrslam_agent_cooperation)
# Peers' landmarks streamed with their raw measurements: placed through the frame transform, a
# mover predicted, left out where the robot's own lidar has reached or where the map holds one.
mrslam_add_test(streamed_landmarks_test
  SOURCES streamed_landmarks_test.cc
  LIBS mrslam_agent_cooperation)
# Where a robot's lidar has reached: marked cells kept as the grid grows to new places.
mrslam_add_test(reach_grid_test
  SOURCES reach_grid_test.cc
  LIBS mrslam_agent_cooperation)
