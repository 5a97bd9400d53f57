# EKF-SLAM and paper B's expected-landmark-area test: Jacobians against numeric differences, the
# Joseph-form update (SPD property test), map merging, the ELA test and ekf_ela in a static world.
mrslam_add_test(ekf_slam_test
  SOURCES ekf_slam_test.cc
  LIBS mrslam_agent_factory mrslam_config)
mrslam_add_test(ela_test
  SOURCES ela_test.cc
  LIBS mrslam_agent_filters mrslam_config mrslam_world_core mrslam_metrics)
