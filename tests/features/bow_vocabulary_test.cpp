// BowVocabulary against known truth: descriptors drawn as noisy copies of known prototypes
// (the true clusters), idf weights against log(N / n_i) counted from the construction, the
// L1 score against hand-computed values, and the file format against corruption.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <set>

#include "core/errors.hpp"
#include "features/bow_vocabulary.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

// Binary prototypes (random 256-bit strings, ~128 bits apart) and copies with `flips` bits flipped.
std::vector<cv::Mat> binary_prototypes(int n, std::mt19937& rng) {
  std::vector<cv::Mat> out;
  for (int p = 0; p < n; ++p) {
    cv::Mat m(1, 32, CV_8U);
    for (int b = 0; b < 32; ++b) m.at<std::uint8_t>(0, b) = static_cast<std::uint8_t>(rng() & 0xff);
    out.push_back(m);
  }
  return out;
}

cv::Mat noisy_binary(const cv::Mat& proto, int flips, std::mt19937& rng) {
  cv::Mat m = proto.clone();
  std::uniform_int_distribution<int> bit(0, 255);
  for (int i = 0; i < flips; ++i) {
    const int b = bit(rng);
    m.at<std::uint8_t>(0, b / 8) ^= static_cast<std::uint8_t>(1u << (b % 8));
  }
  return m;
}

std::vector<cv::Mat> float_prototypes(int n, int dim, std::mt19937& rng) {
  std::normal_distribution<float> g(0, 1);
  std::vector<cv::Mat> out;
  for (int p = 0; p < n; ++p) {
    cv::Mat m(1, dim, CV_32F);
    for (int i = 0; i < dim; ++i) m.at<float>(0, i) = 5.0f * g(rng);
    out.push_back(m);
  }
  return out;
}

cv::Mat noisy_float(const cv::Mat& proto, float sigma, std::mt19937& rng) {
  std::normal_distribution<float> g(0, sigma);
  cv::Mat m = proto.clone();
  for (int i = 0; i < m.cols; ++i) m.at<float>(0, i) += g(rng);
  return m;
}

// Each image holds `per_image` noisy copies of every prototype; returns images and the
// prototype of every row (image-major).
struct Labelled {
  std::vector<cv::Mat> images;
  std::vector<std::vector<int>> label;
};

template <typename Noisy>
Labelled make_images(const std::vector<cv::Mat>& protos, int n_images, int per_image, Noisy noisy) {
  Labelled out;
  for (int i = 0; i < n_images; ++i) {
    cv::Mat img;
    std::vector<int> lab;
    for (int p = 0; p < static_cast<int>(protos.size()); ++p)
      for (int c = 0; c < per_image; ++c) {
        img.push_back(noisy(protos[static_cast<std::size_t>(p)]));
        lab.push_back(p);
      }
    out.images.push_back(img);
    out.label.push_back(lab);
  }
  return out;
}

// Words are pure: no word holds descriptors of two prototypes; and fresh copies land on a
// word that the same prototype's training copies reached.
template <typename Noisy>
void expect_clusters_recovered(const BowVocabulary& voc, const Labelled& data, const std::vector<cv::Mat>& protos,
                               Noisy noisy) {
  std::map<WordId, std::set<int>> protos_of_word;
  std::map<int, std::set<WordId>> words_of_proto;
  for (std::size_t i = 0; i < data.images.size(); ++i)
    for (int r = 0; r < data.images[i].rows; ++r) {
      const WordId w = voc.word_of(data.images[i], r);
      protos_of_word[w].insert(data.label[i][static_cast<std::size_t>(r)]);
      words_of_proto[data.label[i][static_cast<std::size_t>(r)]].insert(w);
    }
  for (const auto& [w, ps] : protos_of_word) EXPECT_EQ(ps.size(), 1u) << "word " << w << " mixes prototypes";
  int recalled = 0, total = 0;
  for (int p = 0; p < static_cast<int>(protos.size()); ++p)
    for (int c = 0; c < 10; ++c) {
      const cv::Mat q = noisy(protos[static_cast<std::size_t>(p)]);
      recalled += words_of_proto[p].count(voc.word_of(q, 0)) > 0;
      ++total;
    }
  EXPECT_GE(recalled, total * 95 / 100) << recalled << " of " << total;
}

TEST(BowVocabulary, BinaryOneLevelFindsTheTrueClusters) {
  std::mt19937 rng(7);
  const auto protos = binary_prototypes(8, rng);
  auto noisy = [&](const cv::Mat& p) { return noisy_binary(p, 12, rng); };
  const auto data = make_images(protos, 6, 5, noisy);
  const auto voc = BowVocabulary::train(data.images, {.k = 8, .levels = 1, .max_iterations = 10, .seed = 3});
  EXPECT_EQ(voc.word_count(), 8u);
  EXPECT_EQ(voc.kind(), DescriptorKind::kBinary);
  expect_clusters_recovered(voc, data, protos, noisy);
  // Majority centre of a cluster of 12-bit-flip copies is (almost) the prototype itself.
  for (const auto& p : protos) {
    const WordId w = voc.word_of(p, 0);
    const auto node = static_cast<std::size_t>([&] {
      for (std::size_t i = 0; i < voc.node_count(); ++i)
        if (voc.node(i).word == static_cast<int>(w)) return i;
      return std::size_t{0};
    }());
    EXPECT_LE(hamming(voc.centre(node).ptr<std::uint8_t>(0), p.ptr<std::uint8_t>(0), 32), 4);
  }
}

TEST(BowVocabulary, BinaryHierarchyKeepsWordsPure) {
  std::mt19937 rng(11);
  const auto protos = binary_prototypes(40, rng);
  auto noisy = [&](const cv::Mat& p) { return noisy_binary(p, 10, rng); };
  const auto data = make_images(protos, 5, 4, noisy);
  const auto voc = BowVocabulary::train(data.images, {.k = 5, .levels = 3, .max_iterations = 10, .seed = 5});
  EXPECT_GE(voc.word_count(), 40u);
  EXPECT_LE(voc.word_count(), 125u);
  for (std::size_t i = 0; i < voc.node_count(); ++i) {
    EXPECT_LE(voc.node(i).children.size(), 5u);
    EXPECT_LE(voc.node(i).depth, 3);
  }
  expect_clusters_recovered(voc, data, protos, noisy);
}

TEST(BowVocabulary, FloatDescriptorsUseMeansAndL2) {
  std::mt19937 rng(13);
  const auto protos = float_prototypes(6, 16, rng);
  auto noisy = [&](const cv::Mat& p) { return noisy_float(p, 0.3f, rng); };
  const auto data = make_images(protos, 5, 6, noisy);
  const auto voc = BowVocabulary::train(data.images, {.k = 6, .levels = 1, .max_iterations = 10, .seed = 2});
  EXPECT_EQ(voc.kind(), DescriptorKind::kFloat);
  EXPECT_EQ(voc.word_count(), 6u);
  expect_clusters_recovered(voc, data, protos, noisy);
  // The centre is the mean of 30 copies with sigma 0.3: within ~0.3 / sqrt(30) * sqrt(16) of the prototype.
  for (const auto& p : protos) {
    const WordId w = voc.word_of(p, 0);
    for (std::size_t i = 0; i < voc.node_count(); ++i)
      if (voc.node(i).word == static_cast<int>(w)) {
        EXPECT_LT(l2_distance(voc.centre(i).ptr<float>(0), p.ptr<float>(0), 16), 0.5f);
      }
  }
}

TEST(BowVocabulary, IdfIsLogOfImagesOverImagesWithTheWord) {
  std::mt19937 rng(17);
  const auto protos = binary_prototypes(5, rng);
  // Prototype p appears in the images i with i % (p + 1) == 0: n_p = ceil(N / (p + 1)).
  const int N = 12;
  std::vector<cv::Mat> images;
  for (int i = 0; i < N; ++i) {
    cv::Mat img;
    for (int p = 0; p < 5; ++p)
      if (i % (p + 1) == 0)
        for (int c = 0; c < 3; ++c) img.push_back(noisy_binary(protos[static_cast<std::size_t>(p)], 8, rng));
    images.push_back(img);
  }
  const auto voc = BowVocabulary::train(images, {.k = 5, .levels = 1, .max_iterations = 10, .seed = 1});
  ASSERT_EQ(voc.word_count(), 5u);
  for (int p = 0; p < 5; ++p) {
    const int n_p = (N + p) / (p + 1);
    EXPECT_NEAR(voc.word_weight(voc.word_of(protos[static_cast<std::size_t>(p)], 0)), std::log(double(N) / n_p), 1e-12) << p;
  }
  // TF-IDF of an image with 2 copies of prototype 1 and 1 of prototype 2, L1-normalised.
  cv::Mat img;
  img.push_back(noisy_binary(protos[1], 8, rng));
  img.push_back(noisy_binary(protos[1], 8, rng));
  img.push_back(noisy_binary(protos[2], 8, rng));
  BowVector v;
  voc.transform(img, v);
  const double a = 2 * std::log(12.0 / 6), b = std::log(12.0 / 4);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_NEAR(v[voc.word_of(protos[1], 0)], a / (a + b), 1e-12);
  EXPECT_NEAR(v[voc.word_of(protos[2], 0)], b / (a + b), 1e-12);
  // Prototype 0 is in every image: idf 0, so it is left out of the vector.
  cv::Mat only0 = noisy_binary(protos[0], 8, rng);
  voc.transform(only0, v);
  EXPECT_TRUE(v.empty());
}

TEST(BowVector, L1ScoreMatchesHandComputedValues) {
  const BowVector a{{1, 0.5}, {2, 0.5}};
  const BowVector b{{2, 0.5}, {3, 0.5}};
  const BowVector c{{4, 0.25}, {5, 0.75}};
  const BowVector d{{1, 0.2}, {2, 0.3}, {7, 0.5}};
  EXPECT_DOUBLE_EQ(bow_l1_score(a, a), 1.0);
  EXPECT_DOUBLE_EQ(bow_l1_score(a, b), 0.5);  // |a-b|_1 = 0.5 + 0 + 0.5
  EXPECT_DOUBLE_EQ(bow_l1_score(a, c), 0.0);
  EXPECT_NEAR(bow_l1_score(a, d), 1 - 0.5 * (0.3 + 0.2 + 0.5), 1e-12);
  EXPECT_NEAR(bow_l1_score(d, a), bow_l1_score(a, d), 1e-15);
}

TEST(BowVocabulary, DirectIndexGroupsEveryFeatureUnderItsNodeAtTheDepth) {
  std::mt19937 rng(19);
  const auto protos = binary_prototypes(30, rng);
  auto noisy = [&](const cv::Mat& p) { return noisy_binary(p, 10, rng); };
  const auto data = make_images(protos, 4, 3, noisy);
  const auto voc = BowVocabulary::train(data.images, {.k = 4, .levels = 3, .max_iterations = 10, .seed = 9});
  BowVector v;
  FeatureVector fv;
  voc.transform(data.images[0], v, &fv, 1);
  double sum = 0;
  for (const auto& [w, x] : v) sum += x;
  EXPECT_NEAR(sum, 1.0, 1e-12);
  std::set<int> rows;
  for (const auto& [node, feats] : fv) {
    EXPECT_EQ(voc.node(node).depth, 1);
    for (int r : feats) {
      EXPECT_TRUE(rows.insert(r).second);
      // The word of the row lies in the subtree of the node.
      int n = -1;
      const WordId w = voc.word_of(data.images[0], r);
      for (std::size_t i = 0; i < voc.node_count(); ++i)
        if (voc.node(i).word == static_cast<int>(w)) n = static_cast<int>(i);
      while (n >= 0 && voc.node(static_cast<std::size_t>(n)).depth > 1) n = voc.node(static_cast<std::size_t>(n)).parent;
      EXPECT_EQ(n, static_cast<int>(node));
    }
  }
  EXPECT_EQ(rows.size(), static_cast<std::size_t>(data.images[0].rows));
}

class BowVocabularyFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::scratch_dir("bow_test");
    std::mt19937 rng(23);
    protos_ = binary_prototypes(20, rng);
    data_ = make_images(protos_, 4, 3, [&](const cv::Mat& p) { return noisy_binary(p, 10, rng); });
    voc_ = BowVocabulary::train(data_.images, {.k = 4, .levels = 3, .max_iterations = 10, .seed = 4});
    path_ = dir_ / "v.bsvoc";
    voc_.save(path_);
    std::ifstream f(path_, std::ios::binary);
    bytes_.assign((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path write(const std::string& name, const std::string& bytes) {
    const auto p = dir_ / name;
    std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return p;
  }
  void expect_rejected(const std::filesystem::path& p) {
    try {
      BowVocabulary::load(p);
      FAIL() << "accepted " << p;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
    }
  }
  std::filesystem::path dir_, path_;
  std::vector<cv::Mat> protos_;
  Labelled data_;
  BowVocabulary voc_;
  std::string bytes_;
};

TEST_F(BowVocabularyFile, RoundTripGivesTheSameWordsAndWeights) {
  const auto loaded = BowVocabulary::load(path_);
  EXPECT_EQ(loaded.word_count(), voc_.word_count());
  EXPECT_EQ(loaded.k(), 4);
  EXPECT_EQ(loaded.levels(), 3);
  for (const auto& img : data_.images) {
    BowVector a, b;
    voc_.transform(img, a);
    loaded.transform(img, b);
    EXPECT_EQ(a, b);
  }
}

TEST_F(BowVocabularyFile, SameSeedSameBytes) {
  const auto again = BowVocabulary::train(data_.images, {.k = 4, .levels = 3, .max_iterations = 10, .seed = 4});
  again.save(dir_ / "again.bsvoc");
  std::ifstream f(dir_ / "again.bsvoc", std::ios::binary);
  const std::string b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_EQ(b, bytes_);
}

TEST_F(BowVocabularyFile, CorruptTruncatedForeignAndNewerFilesAreRejected) {
  for (std::size_t cut : {std::size_t{3}, std::size_t{20}, bytes_.size() / 2, bytes_.size() - 1})
    expect_rejected(write("cut" + std::to_string(cut) + ".bsvoc", bytes_.substr(0, cut)));
  for (std::size_t at : {std::size_t{30}, bytes_.size() / 3, bytes_.size() - 3}) {
    std::string b = bytes_;
    b[at] = static_cast<char>(b[at] ^ 0x10);
    expect_rejected(write("flip" + std::to_string(at) + ".bsvoc", b));
  }
  expect_rejected(write("foreign.bsvoc", std::string("\x89PNG\r\n\x1a\n", 8) + std::string(100, 'x')));
  std::string newer = bytes_;
  newer[8] = 2;
  expect_rejected(write("newer.bsvoc", newer));
  expect_rejected(dir_ / "missing.bsvoc");
}

TEST(BowVocabulary, BadTrainingInputAndMismatchedDescriptorsAreInputErrors) {
  EXPECT_THROW(BowVocabulary::train({}), InputError);
  EXPECT_THROW(BowVocabulary::train({cv::Mat(3, 32, CV_8U, cv::Scalar(1))}, {.k = 1}), InputError);
  EXPECT_THROW(BowVocabulary::train({cv::Mat(3, 32, CV_8U, cv::Scalar(1)), cv::Mat(3, 8, CV_32F, cv::Scalar(1))}), InputError);
  std::mt19937 rng(29);
  const auto protos = binary_prototypes(4, rng);
  const auto data = make_images(protos, 2, 3, [&](const cv::Mat& p) { return noisy_binary(p, 5, rng); });
  const auto voc = BowVocabulary::train(data.images, {.k = 4, .levels = 1});
  BowVector v;
  EXPECT_THROW(voc.transform(cv::Mat(2, 16, CV_32F, cv::Scalar(0)), v), InputError);
  EXPECT_THROW(voc.transform(cv::Mat(2, 16, CV_8U, cv::Scalar(0)), v), InputError);
}

}  // namespace
}  // namespace builtscene
