# The agent's message conversions at the DDS edge (round trips).
mrslam_add_test(agent_msg_conversion_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/agent_msg_conversion_test.cc
  LIBS mrslam_agent_node)

# Sample validation in the filter core.
mrslam_add_test(sample_validation_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/sample_validation_test.cc
  LIBS mrslam_agent_cooperation)

# Which sensor samples an agent takes (the simulator's, within the horizon) and how it counts the rest.
mrslam_add_test(sample_intake_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/sample_intake_test.cc
  LIBS mrslam_agent_cooperation)
