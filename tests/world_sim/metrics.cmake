# Unit tests of the metric functions (world_sim/evaluator/metrics.h).
mrslam_add_test(metrics_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/metrics_test.cc
  LIBS mrslam_metrics)
