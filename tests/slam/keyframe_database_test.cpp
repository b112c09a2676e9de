// KeyFrameDatabase against constructed places: every keyframe of place p holds noisy copies
// of place p's own descriptors, so the truth of "which keyframes show the place a query
// shows" is known by construction.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "features/bow_vocabulary.hpp"
#include "slam/key_frame.hpp"
#include "slam/keyframe_database.hpp"

namespace builtscene::slam {
namespace {

constexpr int kPlaces = 6;
constexpr int kPerPlace = 300;  // distinct descriptors of one place
constexpr int kSeen = 200;      // a view sees this many of them

class Places {
 public:
  Places() : rng_(31) {
    for (int p = 0; p < kPlaces; ++p) {
      cv::Mat m(kPerPlace, 32, CV_8U);
      for (int r = 0; r < kPerPlace; ++r)
        for (int b = 0; b < 32; ++b) m.at<std::uint8_t>(r, b) = static_cast<std::uint8_t>(rng_() & 0xff);
      protos_.push_back(m);
    }
    ctx_ = std::make_shared<FrameContext>();
  }

  // A view of place p: noisy copies of a random subset of its descriptors.
  cv::Mat view(int p) {
    std::vector<int> idx(kPerPlace);
    for (int i = 0; i < kPerPlace; ++i) idx[static_cast<std::size_t>(i)] = i;
    std::shuffle(idx.begin(), idx.end(), rng_);
    cv::Mat m(kSeen, 32, CV_8U);
    std::uniform_int_distribution<int> bit(0, 255);
    for (int r = 0; r < kSeen; ++r) {
      protos_[static_cast<std::size_t>(p)].row(idx[static_cast<std::size_t>(r)]).copyTo(m.row(r));
      for (int f = 0; f < 12; ++f) {
        const int b = bit(rng_);
        m.at<std::uint8_t>(r, b / 8) ^= static_cast<std::uint8_t>(1u << (b % 8));
      }
    }
    return m;
  }

  std::shared_ptr<KeyFrame> keyframe(long id, int place) {
    auto f = std::make_shared<FrameFeatures>();
    f->ctx = ctx_;
    f->descriptors = view(place);
    f->keys_un.assign(kSeen, cv::KeyPoint());
    f->keys = f->keys_un;
    f->depth.assign(kSeen, -1.0f);
    f->u_right.assign(kSeen, -1.0f);
    Frame frame(id, static_cast<double>(id), f);
    return std::make_shared<KeyFrame>(id, frame);
  }

 private:
  std::mt19937 rng_;
  std::vector<cv::Mat> protos_;
  std::shared_ptr<FrameContext> ctx_;
};

struct DatabaseFixture : ::testing::Test {
  void SetUp() override {
    std::vector<cv::Mat> training;
    for (int p = 0; p < kPlaces; ++p)
      for (int i = 0; i < 4; ++i) training.push_back(places.view(p));
    auto voc = std::make_shared<BowVocabulary>(BowVocabulary::train(training, {.k = 10, .levels = 4, .max_iterations = 10, .seed = 1}));
    db = std::make_unique<KeyFrameDatabase>(voc, 1);
    long id = 0;
    for (int p = 0; p < kPlaces; ++p) {
      std::vector<std::shared_ptr<KeyFrame>> group;
      for (int i = 0; i < 3; ++i) {
        auto kf = places.keyframe(id++, p);
        place_of[kf.get()] = p;
        group.push_back(kf);
        kfs.push_back(kf);
      }
      // Keyframes of one place are covisible.
      for (auto& a : group)
        for (auto& b : group)
          if (a != b) a->add_connection(b.get(), 50);
    }
    for (auto& kf : kfs) db->add(kf);
  }
  Places places;
  std::unique_ptr<KeyFrameDatabase> db;
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  std::map<const KeyFrame*, int> place_of;
};

TEST_F(DatabaseFixture, RelocalizationCandidatesShowThePlaceOfTheQuery) {
  EXPECT_EQ(db->size(), static_cast<std::size_t>(kPlaces * 3));
  for (int p = 0; p < kPlaces; ++p) {
    BowVector bow;
    FeatureVector fv;
    db->compute_bow(places.view(p), bow, fv);
    const auto c = db->relocalization_candidates(bow);
    ASSERT_FALSE(c.empty()) << "place " << p;
    for (KeyFrame* kf : c) EXPECT_EQ(place_of[kf], p) << "place " << p << " returned keyframe " << kf->id;
    // The same place scores far above another place.
    const double same = bow_l1_score(bow, c.front()->bow);
    const double other = bow_l1_score(bow, kfs[static_cast<std::size_t>(((p + 1) % kPlaces) * 3)]->bow);
    EXPECT_GT(same, 3 * other);
  }
}

TEST_F(DatabaseFixture, LoopCandidatesExcludeConnectedKeyframes) {
  // A new keyframe at place 2 not yet connected: the place's keyframes are loop candidates.
  auto fresh = places.keyframe(100, 2);
  BowVector bow;
  db->compute_bow(fresh->f->descriptors, fresh->bow, fresh->bow_features);
  auto c = db->loop_candidates(*fresh, 0.1);
  ASSERT_FALSE(c.empty());
  for (KeyFrame* kf : c) EXPECT_EQ(place_of[kf], 2);
  // Connected to every keyframe of place 2: nothing else shows the place.
  for (const auto& kf : kfs)
    if (place_of[kf.get()] == 2) fresh->add_connection(kf.get(), 40);
  c = db->loop_candidates(*fresh, 0.1);
  for (KeyFrame* kf : c) EXPECT_NE(place_of[kf], 2);
  EXPECT_TRUE(c.empty());
  // A minimum score above any achievable one leaves nothing.
  auto other = places.keyframe(101, 4);
  db->compute_bow(other->f->descriptors, other->bow, other->bow_features);
  EXPECT_TRUE(db->loop_candidates(*other, 1.01).empty());
}

TEST_F(DatabaseFixture, BadKeyframesAreNeverReturnedAndArePurged) {
  for (const auto& kf : kfs)
    if (place_of[kf.get()] == 3) kf->bad = true;
  BowVector bow;
  FeatureVector fv;
  db->compute_bow(places.view(3), bow, fv);
  for (KeyFrame* kf : db->relocalization_candidates(bow)) EXPECT_NE(place_of[kf], 3);
  db->purge_bad();
  EXPECT_EQ(db->size(), static_cast<std::size_t>((kPlaces - 1) * 3));
  db->erase(kfs[0].get());
  EXPECT_EQ(db->size(), static_cast<std::size_t>((kPlaces - 1) * 3 - 1));
  db->compute_bow(places.view(0), bow, fv);
  for (KeyFrame* kf : db->relocalization_candidates(bow)) EXPECT_NE(kf, kfs[0].get());
}

}  // namespace
}  // namespace builtscene::slam
