# Unit tests of the metric functions (world_sim/evaluator/metrics.h).
mrslam_add_test(metrics_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/metrics_test.cc
  LIBS mrslam_metrics)

# The run scorer (summary.json) on hand-made runs.
mrslam_add_test(run_evaluator_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/run_evaluator_test.cc
  LIBS mrslam_run_evaluator)

# One robot's step-by-step scorer, shared by the evaluator and the batch tools.
mrslam_add_test(robot_scorer_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/robot_scorer_test.cc
  LIBS mrslam_metrics)

# Paper B's metrics of a run, as the experiment grid reports them.
mrslam_add_test(paper_b_scorer_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/paper_b_scorer_test.cc
  LIBS mrslam_metrics)

# The run step by step as the viewer shows it (view.jsonl).
mrslam_add_test(view_steps_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/view_steps_test.cc
  LIBS mrslam_run_evaluator)

# The delivery figures of a run (latency beyond processing, late estimates).
mrslam_add_test(delivery_timing_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/delivery_timing_test.cc
  LIBS mrslam_run_evaluator)

# A robot's true path by step, kept for scoring its final trajectory.
mrslam_add_test(truth_path_test
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/truth_path_test.cc
  LIBS mrslam_run_evaluator)
