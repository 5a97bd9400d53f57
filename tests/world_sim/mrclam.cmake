# The MRCLAM reader and replay (world_sim/replay/): excerpt, broken copies, Dataset 6 if present.
mrslam_add_test(mrclam_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mrclam_test.cc
  LIBS mrslam_world_source mrslam_agent_cooperation mrslam_agent_factory mrslam_config)
