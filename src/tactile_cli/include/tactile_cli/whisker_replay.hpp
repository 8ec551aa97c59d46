// `tactile replay`: whisker_driver (bag source) -> tdorc_filter over a bag of
// raw whisker pressures, with an evaluation of the three drift-compensation
// modes (paper 000, TDORC section and Extended Data Fig. 2).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace tactile_cli {

struct ReplayOptions {
  std::string bag;          ///< input rosbag2 directory with tactile_msgs/WhiskerPressure topics
  std::string out_dir;      ///< receives bag/, metrics.json, signals.png
  std::string config_dir;   ///< parameter YAML files (config/)
  bool write_png = true;
};

/// Runs the replay and writes its outputs; returns the metrics (also written
/// to out_dir/metrics.json). Throws std::runtime_error (or BagError /
/// ParamError) with a message naming the file and the reason.
///
/// Metrics: fpr_bandpass, fpr_tdoc, fpr_tdorc = FP / (FP + TN) over every
/// (sample, channel) pair that is a true negative candidate: all samples where
/// the bag's ground truth (tactile_msgs/WhiskerGroundTruth topics, if present)
/// says no contact, or every sample if the bag has no ground truth (a
/// free-flight recording). Samples are counted once all three modes have a
/// drift fit (the first window). contact_detected: TDORC flagged contact
/// during a true contact (or anywhere, without ground truth).
nlohmann::json run_replay(const ReplayOptions& options);

}  // namespace tactile_cli
