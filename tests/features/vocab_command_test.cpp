// `builtscene vocab train` and the SLAM's --vocabulary option from the command line: bad
// input exits 2 with a message naming the option or file; training is deterministic; the
// shipped vocabulary loads and is an ORB (binary, 32-byte) vocabulary of the documented shape.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "features/bow_vocabulary.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::shell_quote;

const fs::path kKitchen = fs::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen";
const fs::path kShipped = fs::path(BUILTSCENE_SOURCE_DIR) / "data/vocab/orb_k10_L4.bsvoc";

// A file `name` in this process's folder `bs_vocab_cmd_<pid>` (made once, removed at exit).
fs::path temp(const std::string& name) {
  static const fs::path d = testing::scratch_dir("vocab_cmd");
  return d / name;
}

std::string bytes_of(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

TEST(VocabCommand, BadInputExitsTwoNamingTheProblem) {
  const auto out = temp("bad.bsvoc");
  auto r = run_cli("vocab train --out " + shell_quote(out));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--dataset"), std::string::npos) << r.err;
  r = run_cli("vocab train --dataset " + shell_quote(kKitchen) + " --k 1 --out " + shell_quote(out));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--k"), std::string::npos) << r.err;
  r = run_cli("vocab train --images /nonexistent-folder --out " + shell_quote(out));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nonexistent-folder"), std::string::npos) << r.err;
  fs::remove(out);
}

TEST(VocabCommand, TrainingIsDeterministicAndLoadable) {
  if (!fs::exists(kKitchen / "rgb.txt")) GTEST_SKIP() << "7scenes-kitchen not found";
  const auto a = temp("a.bsvoc"), b = temp("b.bsvoc");
  const std::string args = " --dataset " + shell_quote(kKitchen) + " --max-frames 6 --k 6 --levels 3 --seed 5 --json --out ";
  const auto ra = run_cli("vocab train" + args + shell_quote(a));
  const auto rb = run_cli("vocab train" + args + shell_quote(b));
  ASSERT_EQ(ra.exit_code, 0) << ra.err;
  ASSERT_EQ(rb.exit_code, 0) << rb.err;
  EXPECT_EQ(bytes_of(a), bytes_of(b));
  const auto j = nlohmann::json::parse(ra.out);
  EXPECT_EQ(j["images"].get<int>(), 6);
  const auto voc = BowVocabulary::load(a);
  EXPECT_EQ(voc.word_count(), j["words"].get<std::size_t>());
  EXPECT_LE(voc.word_count(), 6u * 6u * 6u);
  EXPECT_EQ(voc.kind(), DescriptorKind::kBinary);
  fs::remove(a);
  fs::remove(b);
}

TEST(VocabCommand, ShippedVocabularyIsAnOrbTreeOfTheDocumentedShape) {
  const auto voc = BowVocabulary::load(kShipped);
  EXPECT_EQ(voc.kind(), DescriptorKind::kBinary);
  EXPECT_EQ(voc.descriptor_cols(), 32);
  EXPECT_EQ(voc.k(), 10);
  EXPECT_EQ(voc.levels(), 4);
  EXPECT_GT(voc.word_count(), 5000u);
  EXPECT_LT(fs::file_size(kShipped), 1000000u);
}

TEST(VocabCommand, SlamRejectsACorruptVocabularyNamingTheFile) {
  if (!fs::exists(kKitchen / "rgb.txt")) GTEST_SKIP() << "7scenes-kitchen not found";
  const auto bad = temp("corrupt.bsvoc");
  std::string b = bytes_of(kShipped);
  b[b.size() / 2] = static_cast<char>(b[b.size() / 2] ^ 0x40);
  std::ofstream(bad, std::ios::binary).write(b.data(), static_cast<std::streamsize>(b.size()));
  const auto traj = temp("traj.txt");
  const auto r = run_cli("slam --dataset " + shell_quote(kKitchen) + " --max-frames 2 --trajectory " + shell_quote(traj) +
                         " --vocabulary " + shell_quote(bad));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad.filename().string()), std::string::npos) << r.err;
  fs::remove(bad);
  fs::remove(traj);
}

}  // namespace
}  // namespace builtscene
