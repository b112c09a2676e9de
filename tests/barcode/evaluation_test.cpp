#include "barcode/evaluation.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "core/errors.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::barcode {
namespace {

TEST(Evaluation, RatesReadsAndFalseCodesByHand) {
  const std::vector<TruthLabel> truth = {{"RM1401A", "Code128", "location", 10},
                                         {"RM1402A", "Code128", "location", 4},
                                         {"RM1403A", "Code128", "location", 0},  // never legible
                                         {"P100001", "Code39", "product", 3}};
  Inventory inv;
  inv.add(1, "RM1401A", "Code128", {});
  inv.add(2, "RM1401A", "Code128", {});
  inv.add(3, "P100001", "Code39", {});
  inv.add(3, "RM1401A", "Code39", {});  // right text, wrong symbology: a false code
  inv.add(4, "XYZ", "Code128", {});
  const auto e = evaluate(truth, inv);
  EXPECT_EQ(e.labels, 4u);
  EXPECT_EQ(e.legible_labels, 3u);
  EXPECT_EQ(e.recognized, 2u);
  EXPECT_DOUBLE_EQ(e.recognition_rate, 2.0 / 3.0);
  EXPECT_EQ(e.location_labels, 3u);
  EXPECT_EQ(e.location_recognized, 1u);
  EXPECT_EQ(e.reads, 3u);
  EXPECT_EQ(e.false_codes, 2u);
  EXPECT_EQ(e.missed, (std::vector<std::string>{"RM1402A"}));
}

TEST(Evaluation, TruthFileErrorsNameTheFile) {
  const auto f = builtscene::testing::scratch_dir("truth") / "bs_truth.csv";
  std::ofstream(f) << "text,kind\nRM1401A,location\n";
  try {
    read_truth(f);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("symbology"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find(f.filename().string()), std::string::npos);
  }
  std::filesystem::remove(f);
}

TEST(Evaluation, SweepHasTheSourcesColumns) {
  const auto cols = sweep_columns({});
  ASSERT_EQ(cols.size(), 16u);
  EXPECT_TRUE(cols[0].options.decoder_only);
  EXPECT_EQ(cols[1].options.region, "0.3");
  EXPECT_FALSE(cols[1].options.rotate);
  EXPECT_TRUE(cols[8].options.rotate);
  EXPECT_FALSE(cols[8].options.whole_frame);
  EXPECT_TRUE(cols[9].options.whole_frame);
  EXPECT_EQ(cols[15].options.keyframes, "1.0");
}

}  // namespace
}  // namespace builtscene::barcode
