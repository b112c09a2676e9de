#pragma once
// Evaluation of an inventory against a truth file (truth.csv of a generated scan): recognition
// rate, successful reads, false codes; and the parameter sweep of the source's Figures 4.12-4.14.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "barcode/inventory.hpp"
#include "barcode/scan_pipeline.hpp"

namespace builtscene::barcode {

struct TruthLabel {
  std::string text;
  std::string symbology;
  std::string kind;             // "location", "product" or empty
  std::size_t legible_count = 0;  // frames in which it is legible by construction
};

// Reads truth.csv: columns text, symbology; optional kind, legible_count. InputError names the
// file and line at fault.
std::vector<TruthLabel> read_truth(const std::filesystem::path& file);

struct Evaluation {
  std::size_t labels = 0;          // labels in the truth
  std::size_t legible_labels = 0;  // labels legible in at least one frame (the denominator)
  std::size_t recognized = 0;      // legible labels read at least once
  double recognition_rate = 0;     // recognized / legible_labels
  std::size_t location_labels = 0, location_recognized = 0;
  double location_recognition_rate = 0;
  std::size_t reads = 0;           // reads of true codes
  std::size_t false_codes = 0;     // distinct decoded texts not in the truth
  std::vector<std::string> false_code_texts;
  std::vector<std::string> missed;  // legible labels never read
  nlohmann::json to_json() const;
};

Evaluation evaluate(const std::vector<TruthLabel>& truth, const Inventory& inventory);

// One column of a sweep table.
struct SweepColumn {
  std::string name;
  ScanOptions options;
};
// The configurations of Figures 4.12-4.14: decoder only; regions at several thresholds; regions
// with rotation; key frames at 0.5 ... 1.0 times the mean with regions and rotation.
std::vector<SweepColumn> sweep_columns(const ScanOptions& base);

struct SweepResult {
  std::vector<SweepColumn> columns;
  std::vector<ScanResult> scans;
  std::vector<Evaluation> evaluations;
  // Plain-text tables (location labels as rows, per-label reads, totals) like the source's.
  std::string table(const std::vector<TruthLabel>& truth) const;
  nlohmann::json to_json() const;
};
SweepResult run_sweep(const std::filesystem::path& video, const std::vector<TruthLabel>& truth, const ScanOptions& base);

}  // namespace builtscene::barcode
