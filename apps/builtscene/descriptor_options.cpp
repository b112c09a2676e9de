#include "descriptor_options.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "cli_parsing.hpp"
#include "core/errors.hpp"
#include "core/stage_timer.hpp"
#include "features/saft_extractor.hpp"

namespace builtscene::app {

void DescriptorOptions::add_to(CLI::App& cmd) {
  cmd.add_option("--descriptor", descriptor, "Feature descriptor: orb (binary) or saft (learned, docs/saft.md)")
      ->capture_default_str();
  cmd.add_option("--saft-weights", saft_weights, "SAFT weights (default: the shipped data/saft/saft_v1.saft)");
  cmd.add_option("--saft-mode", saft_mode,
                 "SAFT online learning: offline (pre-trained net only), continuous (new weights after every "
                 "training batch) or discrete (after passes over one batch up to --saft-target-accuracy or 20 passes)")
      ->capture_default_str();
  cmd.add_option("--saft-learning-rate", saft_learning_rate, "SAFT online learning rate (fixed)")->capture_default_str();
  cmd.add_option("--saft-target-accuracy", saft_target_accuracy, "Discrete SAFT: training accuracy that releases weights")
      ->capture_default_str();
  cmd.add_option("--saft-anchor", saft_anchor,
                 "SAFT online learning: weight of the pull towards the pre-trained descriptors (0 = none; docs/saft.md)")
      ->capture_default_str();
  cmd.add_flag("--saft-handover-check", saft_handover_check,
               "Continuous SAFT: hold out a quarter of each batch and hand the new weights over only if the "
               "accuracy on it did not fall (else go back; docs/saft.md)");
  cmd.add_flag("--saft-calibrate-decision", saft_calibrate_decision,
               "SAFT online learning: fit the hinge decision to the pre-trained net on the first batch before the "
               "first step (docs/saft.md)");
  cmd.add_option("--saft-weights-out", saft_weights_out, "Output: the SAFT weights at the end of the run (fine-tuned)");
  cmd.add_option("--inliers-out", inliers_out,
                 "Output: CSV per frame of matches and inliers after the initial pose and after local-map tracking");
}

void DescriptorOptions::apply(slam::SystemOptions& so) const {
  so.descriptor = parse_descriptor_choice(descriptor);
  so.saft_weights = saft_weights;
  so.saft_learning.mode = slam::parse_saft_learning_mode(saft_mode);
  if (!(saft_learning_rate > 0 && saft_learning_rate < 1))
    throw InputError("--saft-learning-rate: expected a value in (0, 1), got " + std::to_string(saft_learning_rate));
  if (!(saft_target_accuracy > 0 && saft_target_accuracy <= 1))
    throw InputError("--saft-target-accuracy: expected a value in (0, 1], got " + std::to_string(saft_target_accuracy));
  so.saft_learning.learning_rate = saft_learning_rate;
  so.saft_learning.target_accuracy = saft_target_accuracy;
  if (!(saft_anchor >= 0 && saft_anchor < 1e6)) throw InputError("--saft-anchor: expected a value >= 0, got " + std::to_string(saft_anchor));
  so.saft_learning.anchor_weight = saft_anchor;
  so.saft_learning.handover_check = saft_handover_check;
  so.saft_learning.calibrate_decision = saft_calibrate_decision;
  if (saft_calibrate_decision && so.saft_learning.mode == slam::SaftLearningMode::kOffline)
    throw InputError("--saft-calibrate-decision needs --saft-mode continuous or discrete");
  if (saft_handover_check && so.saft_learning.mode != slam::SaftLearningMode::kContinuous)
    throw InputError("--saft-handover-check needs --saft-mode continuous");
  if (so.descriptor == DescriptorChoice::kOrb && (!saft_weights.empty() || saft_mode != "offline" || !saft_weights_out.empty()))
    throw InputError("--saft-weights, --saft-mode and --saft-weights-out need --descriptor saft");
}

void DescriptorOptions::check_outputs() const {
  for (const auto& out : {saft_weights_out, inliers_out}) check_output_file(out);
}

void TrackingDiagnostics::add(long frame, double timestamp, const slam::TrackingOutcome& out, long weight_updates) {
  rows_.push_back({frame, timestamp, out.initial_matches, out.initial_inliers, out.local_map_matches, out.local_map_inliers,
                   weight_updates});
}

void TrackingDiagnostics::write_csv(const std::filesystem::path& path) const {
  if (path.empty()) return;
  std::ofstream f(path);
  f << "frame,timestamp,initial_matches,initial_inliers,initial_ratio,local_map_matches,local_map_inliers,local_map_ratio,"
       "weight_updates\n";
  auto ratio = [](int inliers, int matches) { return matches > 0 ? static_cast<double>(inliers) / matches : 0.0; };
  for (const auto& r : rows_)
    f << r.frame << ',' << fmt::format("{:.6f}", r.timestamp) << ',' << r.initial_matches << ',' << r.initial_inliers << ','
      << fmt::format("{:.4f}", ratio(r.initial_inliers, r.initial_matches)) << ',' << r.local_matches << ','
      << r.local_inliers << ',' << fmt::format("{:.4f}", ratio(r.local_inliers, r.local_matches)) << ','
      << r.weight_updates << '\n';
  if (!f) throw InputError(located(path, 0, "write failed"));
}

nlohmann::json TrackingDiagnostics::summary(slam::System& system, const DescriptorOptions& opt) const {
  std::vector<double> initial, local;
  for (const auto& r : rows_) {
    if (r.initial_matches > 0) initial.push_back(static_cast<double>(r.initial_inliers) / r.initial_matches);
    if (r.local_matches > 0) local.push_back(static_cast<double>(r.local_inliers) / r.local_matches);
  }
  nlohmann::json j = {{"descriptor", opt.descriptor},
                      {"inlier_ratio_initial_median", quantile(initial, 0.5)},
                      {"inlier_ratio_local_map_median", quantile(local, 0.5)},
                      {"inliers_csv", opt.inliers_out.string()}};
  if (const auto* learning = system.saft_learning()) {
    const auto s = learning->stats();
    j["saft"] = {{"mode", slam::to_string(learning->options().mode)},
                 {"weights", opt.saft_weights.empty() ? SaftNetwork::default_weights_path().string() : opt.saft_weights.string()},
                 {"learning_rate", learning->options().learning_rate},
                 {"anchor_weight", learning->options().anchor_weight},
                 {"batches_prepared", s.batches_prepared},
                 {"batches_dropped", s.batches_dropped},
                 {"batches_trained", s.batches_trained},
                 {"passes", s.passes},
                 {"weight_updates", s.weight_updates},
                 {"target_reached", s.target_reached},
                 {"handover_check", learning->options().handover_check},
                 {"handovers_refused", s.handovers_refused},
                 {"calibrate_decision", learning->options().calibrate_decision},
                 {"frames_per_update", s.weight_updates > 0 ? static_cast<double>(rows_.size()) / s.weight_updates : 0.0},
                 {"first_accuracy", s.first_accuracy},
                 {"last_accuracy", s.last_accuracy},
                 {"decision_first", {{"w", s.first_decision.w}, {"b", s.first_decision.b}}},
                 {"decision_last", {{"w", s.last_decision.w}, {"b", s.last_decision.b}}}};
    if (!opt.saft_weights_out.empty()) {
      system.saft_extractor()->network().save(opt.saft_weights_out);
      j["saft"]["weights_out"] = opt.saft_weights_out.string();
    }
  }
  return j;
}

}  // namespace builtscene::app
