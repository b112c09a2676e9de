// End to end through the CLI: `saft train` learns (its validation FPR95 on generated pairs
// falls far below that of the untrained network), `saft eval` on the held-out real HPatches
// sequences meets the acceptance (SAFT below ORB, normalized below unnormalized), and bad
// input gives a one-line error with exit code 2.
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../common/run_cli.hpp"
#include "test_images.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::shell_quote;

fs::path fresh_dir(const std::string& name) { return testing::scratch_dir("saft_slow_" + name); }

TEST(SaftCli, TrainingLowersValidationFpr95) {
  const fs::path dir = fresh_dir("train");
  fs::create_directories(dir / "images");
  for (int i = 0; i < 14; ++i)
    cv::imwrite((dir / "images" / ("img" + std::to_string(i + 10) + ".png")).string(), test::textured_image(320, 240, 100 + i));
  auto train = [&](int steps) {
    const auto r = run_cli("saft train --images " + shell_quote((dir / "images").string()) + " --every 1 --validation 0.2 --keypoints 200 --warps 3 --steps " +
                           std::to_string(steps) + " --batch 64 --out " + shell_quote((dir / "w.saft").string()) + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out);
  };
  const auto untrained = train(1);
  const auto trained = train(300);
  const double before = untrained["validation"]["saft"]["fpr95"], after = trained["validation"]["saft"]["fpr95"];
  EXPECT_LT(after, 0.5 * before) << "untrained " << before << ", trained " << after;
  EXPECT_LT(trained["weights_bytes"].get<long>(), 1 << 20);
  fs::remove_all(dir);
}

TEST(SaftCli, ShippedWeightsBeatOrbOnHeldOutHpatches) {
  const fs::path data = testing::shared_data() / "hpatches-real";
  if (!fs::exists(data / "v_churchill")) GTEST_SKIP() << data << " is absent: the real HPatches sequences are not on this machine";
  const auto r = run_cli("saft eval --images " + shell_quote((data / "v_churchill").string()) + " " +
                         shell_quote((data / "v_wormhole").string()) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const double orb = j["fpr95"]["orb"], saft = j["fpr95"]["saft"], raw = j["fpr95"]["saft_unnormalized"];
  EXPECT_GT(j["pairs"]["matching"].get<int>(), 1000);
  EXPECT_LT(saft, orb);
  EXPECT_LT(saft, raw);
}

TEST(SaftCli, BadInputIsAOneLineError) {
  const fs::path dir = fresh_dir("bad");
  auto r = run_cli("saft eval --images " + shell_quote((dir / "missing").string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
  fs::create_directories(dir / "seq");
  cv::imwrite((dir / "seq" / "1.png").string(), test::textured_image(100, 100, 1));
  cv::imwrite((dir / "seq" / "2.png").string(), test::textured_image(100, 100, 2));
  std::ofstream(dir / "seq" / "H_1_2") << "1 0 0 0 1 0 0 0";
  r = run_cli("saft eval --images " + shell_quote((dir / "seq").string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("H_1_2"), std::string::npos) << r.err;
  r = run_cli("saft eval --images " + shell_quote((dir / "seq").string()) + " --weights " + shell_quote((dir / "seq" / "1.png").string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("1.png"), std::string::npos) << r.err;
  r = run_cli("saft train --images " + shell_quote((dir / "seq").string()) + " --out " + shell_quote((dir / "w.saft").string()));
  EXPECT_EQ(r.exit_code, 2);  // a homography sequence is held out
  EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace builtscene
