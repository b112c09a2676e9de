#pragma once
// The SAFT descriptor network (the source's chapter 3, sized for a 2-core CPU): 32 x 32
// patch -> four 3 x 3 convolutions (strides 1, 2, 2, 2; batch norm; ReLU) -> a linear layer
// -> 64 floats, L2-normalized for matching. libtorch lives behind the pImpl: this header and
// everything that includes it compile without torch headers.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene {

class SaftTrainer;
class SaftOnlineTrainer;

struct SaftNetworkOptions {
  // Patches per forward pass. Fixed so that every call reuses the same shapes (the last
  // batch is padded); 128 is where the per-patch time stopped falling on this CPU.
  int batch_size = 128;
  // Intra-op threads for this net. One: the SLAM's other threads need the second core.
  int threads = 1;
};

class SaftNetwork {
 public:
  static constexpr int kDimension = 64;

  // A network with freshly initialized (seeded) weights.
  explicit SaftNetwork(SaftNetworkOptions options = {}, unsigned seed = 1);
  // A network with weights from `weights_file` (see save()); InputError naming the file
  // when it is missing, truncated or made for another architecture.
  static SaftNetwork load(const std::filesystem::path& weights_file, SaftNetworkOptions options = {});
  ~SaftNetwork();
  SaftNetwork(SaftNetwork&&) noexcept;
  SaftNetwork& operator=(SaftNetwork&&) noexcept;

  // Weights as raw little-endian float32 tensors after a small header ("BSSAFT01",
  // version, dimension, tensor count, then per tensor its element count and values).
  void save(const std::filesystem::path& weights_file) const;

  // Descriptors of normalized patches (rows of normalize_saft_patches): `unit` gets one
  // L2-normalized CV_32F row of kDimension per patch; `raw`, when given, the same rows
  // before normalization (for the comparison the source makes).
  void describe(const cv::Mat& patches, cv::Mat& unit, cv::Mat* raw = nullptr);

  // Multiply-adds of one forward pass per patch (convolutions and the linear layer),
  // computed from the layer shapes.
  static long multiply_adds_per_patch();
  // Number of stored floats (parameters and batch-norm statistics).
  long parameter_count() const;

  // Every stored float (parameters, then batch-norm statistics, in file order), and back:
  // how fine-tuned weights reach the prediction net (a copy of parameter_count() floats,
  // about 0.1 ms). set_weights throws std::invalid_argument on a length mismatch.
  std::vector<float> weights() const;
  void set_weights(const std::vector<float>& values);

  // The weights shipped in the repository (data/saft/saft_v1.saft in the source tree).
  static std::filesystem::path default_weights_path();

  const SaftNetworkOptions& options() const { return options_; }

 private:
  friend class SaftTrainer;
  friend class SaftOnlineTrainer;
  struct Impl;
  SaftNetworkOptions options_;
  std::unique_ptr<Impl> impl_;
  void warm_up();
};

}  // namespace builtscene
