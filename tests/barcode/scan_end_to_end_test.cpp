// End to end on a generated scan with ground truth by construction (truth.csv): the default
// pipeline against the decoder alone, determinism across thread counts, and the CLI contract.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "barcode/evaluation.hpp"
#include "barcode/scan_pipeline.hpp"
#include "synth/warehouse_scene.hpp"
#include "../common/scratch_dir.hpp"
#include "../common/shell_quote.hpp"

namespace builtscene::barcode {
namespace {
namespace fs = std::filesystem;
using builtscene::testing::shell_quote;

struct GeneratedScan : public ::testing::Test {
  static void SetUpTestSuite() {
    dir = builtscene::testing::scratch_dir("scan_e2e");
    fs::remove_all(dir);
    synth::WarehouseOptions o;
    o.seed = 11;
    o.frames = 360;
    o.size = {1280, 720};
    o.location_labels = 6;
    synth::write_warehouse_scan(dir, o);
  }
  static void TearDownTestSuite() { fs::remove_all(dir); }
  static fs::path dir;
};
fs::path GeneratedScan::dir;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST_F(GeneratedScan, PipelineReadsLabelsWithoutFalseCodesAndAtLeastAsManyAsTheDecoderAlone) {
  const auto truth = read_truth(dir / "truth.csv");
  ScanOptions best;  // the defaults are the best pipeline
  best.out = dir / "best";
  const auto r = scan(dir / "scan.avi", best);
  ScanOptions base;
  base.decoder_only = true;
  base.out = dir / "base";
  const auto b = scan(dir / "scan.avi", base);
  const auto eb = evaluate(truth, r.inventory), ed = evaluate(truth, b.inventory);
  std::cout << "pipeline: " << eb.to_json().dump() << "\nkeyframes " << r.keyframes << "/" << r.frames
            << "\ndecoder only: " << ed.to_json().dump() << "\n";
  EXPECT_EQ(eb.false_codes, 0u);
  EXPECT_EQ(ed.false_codes, 0u);
  EXPECT_LT(r.keyframes, r.frames);
  EXPECT_GE(eb.recognized, ed.recognized);
  EXPECT_GE(eb.recognition_rate, 0.8);
  // The inventory files are what eval reads back.
  EXPECT_EQ(Inventory::read_csv(best.out / "inventory.csv").size(), r.inventory.size());
}

TEST_F(GeneratedScan, OutputIsIdenticalForAnyThreadCount) {
  std::string first;
  for (int threads : {1, 3}) {
    ScanOptions o;
    o.threads = threads;
    o.out = dir / ("threads" + std::to_string(threads));
    o.annotate = false;
    scan(dir / "scan.avi", o);
    const std::string csv = slurp(o.out / "inventory.csv");
    EXPECT_GT(csv.size(), 60u);
    if (first.empty()) {
      first = csv;
    } else {
      EXPECT_EQ(csv, first) << "threads " << threads;
    }
  }
}

int run(const std::string& args) {
  const std::string cmd = shell_quote(BUILTSCENE_BINARY) + " " + args + " > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST_F(GeneratedScan, CliExitCodes) {
  EXPECT_EQ(run("barcodes scan --video " + shell_quote(dir / "missing.avi") + " --out " + shell_quote(dir / "cli")), 2);
  EXPECT_EQ(run("barcodes scan --video " + shell_quote(dir / "scan.avi") + " --out " + shell_quote(dir / "cli") +
                " --region 1.7"),
            2);
  EXPECT_EQ(run("barcodes eval --truth " + shell_quote(dir / "truth.csv") + " --inventory " +
                shell_quote(dir / "nothing.csv")),
            2);
  ASSERT_EQ(run("barcodes scan --video " + shell_quote(dir / "scan.avi") + " --out " + shell_quote(dir / "cli") +
                " --keyframes 0.9 --json"),
            0);
  EXPECT_EQ(run("barcodes eval --truth " + shell_quote(dir / "truth.csv") + " --inventory " +
                shell_quote(dir / "cli" / "inventory.csv") + " --json"),
            0);
}

}  // namespace
}  // namespace builtscene::barcode
