#include "features/patch_verification.hpp"

#include <fstream>
#include <random>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "features/descriptor.hpp"
#include "features/keypoint_warp.hpp"
#include "features/orb_extractor.hpp"
#include "features/saft_patch.hpp"

namespace builtscene {
namespace {

cv::Mat read_gray(const std::filesystem::path& file) {
  cv::Mat img = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw InputError(file.string() + ": missing or not a readable image");
  return img;
}

cv::Matx33d read_homography(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open the homography");
  cv::Matx33d h;
  for (int i = 0; i < 9; ++i) {
    if (!(in >> h.val[i])) throw InputError(file.string() + ": expected 9 numbers (a 3x3 homography), found " + std::to_string(i));
    if (!std::isfinite(h.val[i])) throw InputError(file.string() + ": non-finite value in the homography");
  }
  std::string extra;
  if (in >> extra) throw InputError(file.string() + ": more than 9 values in the homography");
  if (std::abs(cv::determinant(h)) < 1e-12) throw InputError(file.string() + ": singular homography");
  return h;
}

struct Described {
  std::vector<cv::KeyPoint> kps;
  cv::Mat orb, unit, raw;
};

void describe_saft(OrbExtractor& orb, SaftNetwork& net, Described& d) {
  const cv::Mat patches = normalize_saft_patches(sample_saft_patches(orb.levels(), orb.pyramid(), d.kps));
  net.describe(patches, d.unit, &d.raw);
}

}  // namespace

void PatchVerificationDistances::append(const PatchVerificationDistances& o) {
  auto cat = [](std::vector<double>& a, const std::vector<double>& b) { a.insert(a.end(), b.begin(), b.end()); };
  cat(orb_pos, o.orb_pos);
  cat(orb_neg, o.orb_neg);
  cat(saft_pos, o.saft_pos);
  cat(saft_neg, o.saft_neg);
  cat(raw_pos, o.raw_pos);
  cat(raw_neg, o.raw_neg);
}

HomographySequence read_homography_sequence(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) throw InputError(dir.string() + ": not a folder");
  HomographySequence s;
  s.name = dir.filename().string();
  if (s.name.empty()) s.name = dir.parent_path().filename().string();
  s.reference = read_gray(dir / "1.png");
  for (int k = 2;; ++k) {
    const auto img = dir / (std::to_string(k) + ".png");
    const auto hf = dir / ("H_1_" + std::to_string(k));
    if (!std::filesystem::exists(img) && !std::filesystem::exists(hf)) break;
    if (!std::filesystem::exists(hf)) throw InputError(hf.string() + ": missing (image " + img.filename().string() + " has no homography)");
    s.targets.push_back(read_gray(img));
    s.h.push_back(read_homography(hf));
  }
  if (s.targets.empty()) throw InputError(dir.string() + ": no 2.png with H_1_2 (HPatches layout expected)");
  return s;
}

PatchVerificationDistances verify_patches(const HomographySequence& seq, SaftNetwork& net, const PatchVerificationOptions& o) {
  OrbExtractorOptions eo;
  eo.n_features = o.keypoints;
  OrbExtractor orb1(eo), orbk(eo);
  Described ref;
  cv::Mat unused;
  orb1.extract(seq.reference, ref.kps, ref.orb);
  describe_saft(orb1, net, ref);
  const DescriptorMetric hamming = DescriptorMetric::orb();
  const DescriptorMetric l2 = DescriptorMetric::float_l2(SaftNetwork::kDimension);
  std::mt19937_64 rng(o.seed);
  PatchVerificationDistances out;
  for (std::size_t t = 0; t < seq.targets.size(); ++t) {
    Described tgt;
    std::vector<int> index;  // row of ref for each target keypoint
    for (std::size_t i = 0; i < ref.kps.size(); ++i) {
      auto m = warp_keypoint(seq.h[t], ref.kps[i], orb1.pyramid(), seq.targets[t].size(), OrbExtractor::border() + 1);
      if (!m) continue;
      tgt.kps.push_back(*m);
      index.push_back(static_cast<int>(i));
    }
    if (tgt.kps.size() < 2) continue;
    orbk.describe(seq.targets[t], tgt.kps, tgt.orb);
    describe_saft(orbk, net, tgt);
    const int n = static_cast<int>(index.size());
    std::uniform_int_distribution<int> pick(0, n - 1);
    for (int j = 0; j < n; ++j) {
      const int i = index[static_cast<std::size_t>(j)];
      out.orb_pos.push_back(hamming.distance(ref.orb, i, tgt.orb, j));
      out.saft_pos.push_back(l2.distance(ref.unit, i, tgt.unit, j));
      out.raw_pos.push_back(l2.distance(ref.raw, i, tgt.raw, j));
      // One non-matching partner per matching pair: another keypoint's mapped patch.
      for (int attempt = 0; attempt < 50; ++attempt) {
        const int other = pick(rng);
        const cv::Point2f d = ref.kps[static_cast<std::size_t>(index[static_cast<std::size_t>(other)])].pt - ref.kps[static_cast<std::size_t>(i)].pt;
        if (d.dot(d) < o.min_negative_distance * o.min_negative_distance) continue;
        out.orb_neg.push_back(hamming.distance(ref.orb, i, tgt.orb, other));
        out.saft_neg.push_back(l2.distance(ref.unit, i, tgt.unit, other));
        out.raw_neg.push_back(l2.distance(ref.raw, i, tgt.raw, other));
        break;
      }
    }
  }
  return out;
}

}  // namespace builtscene
