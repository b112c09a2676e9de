#include "barcode/inventory.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "core/errors.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::barcode {
namespace {
namespace fs = std::filesystem;

fs::path inventory_dir(const std::string& name) { return builtscene::testing::scratch_dir("barcode_" + name); }

TEST(FrameRanges, FormatAndParse) {
  EXPECT_EQ(format_frame_ranges({3, 4, 5, 6, 7, 12, 20, 21}), "3-7;12;20-21");
  EXPECT_EQ(format_frame_ranges({}), "");
  EXPECT_EQ(parse_frame_ranges("3-7;12;20-21", "x"), (std::vector<std::size_t>{3, 4, 5, 6, 7, 12, 20, 21}));
  EXPECT_THROW(parse_frame_ranges("3-x", "field"), InputError);
  EXPECT_THROW(parse_frame_ranges("9-3", "field"), InputError);
}

TEST(Inventory, DeduplicatesAcrossFramesAndRoundTripsThroughCsv) {
  Inventory inv;
  const cv::Mat small(10, 20, CV_8UC1, cv::Scalar(1)), big(30, 40, CV_8UC1, cv::Scalar(2));
  inv.add(5, "RM1401A", "Code128", small);
  inv.add(6, "RM1401A", "Code128", big);
  inv.add(9, "RM1401A", "Code128", small);
  inv.add(7, "A,B \"quoted\"", "Code39", cv::Mat());
  inv.add(7, "RM1401A", "Code39", cv::Mat());  // same text, other symbology: another code
  ASSERT_EQ(inv.size(), 3u);
  EXPECT_EQ(inv.total_reads(), 5u);
  const auto entries = inv.entries();
  EXPECT_EQ(entries[0]->code, "RM1401A");
  EXPECT_EQ(entries[0]->reads, 3u);
  EXPECT_EQ(entries[0]->first_frame, 5u);
  EXPECT_EQ(entries[0]->last_frame, 9u);
  EXPECT_EQ(entries[0]->best_crop.total(), big.total());

  const fs::path dir = inventory_dir("inv");
  inv.write(dir, {{"frames", 10}});
  EXPECT_TRUE(fs::exists(dir / "inventory.json"));
  EXPECT_TRUE(fs::exists(dir / "crops" / "0.png"));
  const Inventory back = Inventory::read_csv(dir / "inventory.csv");
  ASSERT_EQ(back.size(), 3u);
  EXPECT_TRUE(back.contains("A,B \"quoted\"", "Code39"));
  EXPECT_EQ(back.entries()[0]->frames, (std::vector<std::size_t>{5, 6, 9}));
  fs::remove_all(dir);
}

TEST(Inventory, MalformedCsvNamesFileAndLine) {
  const fs::path dir = inventory_dir("bad");
  std::ofstream(dir / "inv.csv") << "code,symbology,reads,frames\nX,Code128,many,1\n";
  try {
    Inventory::read_csv(dir / "inv.csv");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("inv.csv:2"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "nocol.csv") << "text\nX\n";
  EXPECT_THROW(Inventory::read_csv(dir / "nocol.csv"), InputError);
  EXPECT_THROW(Inventory::read_csv(dir / "missing.csv"), InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace builtscene::barcode
