#include "features/saft_network.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <malloc.h>
#include <stdexcept>
#include <vector>

#include "core/errors.hpp"
#include "features/saft_patch.hpp"
#include "features/saft_torch_net.hpp"

namespace builtscene {
namespace {

constexpr char kWeightsMagic[8] = {'B', 'S', 'S', 'A', 'F', 'T', '0', '1'};
constexpr std::uint32_t kWeightsVersion = 1;

// Parameters, then the batch-norm running statistics (the int64 step counter is not needed
// at inference and is skipped), in registration order: the file's tensor order.
std::vector<torch::Tensor> stored_tensors(saft_detail::SaftNet& net) {
  std::vector<torch::Tensor> out;
  for (auto& p : net->named_parameters()) out.push_back(p.value());
  for (auto& b : net->named_buffers())
    if (b.key().find("num_batches_tracked") == std::string::npos) out.push_back(b.value());
  return out;
}

// libtorch allocates and frees its convolution buffers (several hundred KB each) on every
// forward pass. glibc serves blocks that large with mmap and gives them back with munmap,
// so every pass page-faulted its buffers in again: a 128-patch batch took 95 ms of CPU, a
// quarter of it in the kernel's page-fault path (perf). Keeping large blocks on the heap
// and not trimming it brings the batch to 5 ms (docs/saft.md). Process-wide, set once.
void keep_large_allocations_on_the_heap() {
  static const bool done = [] {
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
    mallopt(M_TOP_PAD, 64 << 20);
    return true;
  }();
  (void)done;
}

}  // namespace

SaftNetwork::SaftNetwork(SaftNetworkOptions options, unsigned seed) : options_(options) {
  keep_large_allocations_on_the_heap();
  if (options_.batch_size < 1) throw InputError("SAFT network: batch_size must be at least 1");
  if (options_.threads < 1) throw InputError("SAFT network: threads must be at least 1");
  torch::set_num_threads(options_.threads);
  impl_ = std::make_unique<Impl>(seed);
  warm_up();
}

SaftNetwork::~SaftNetwork() = default;
SaftNetwork::SaftNetwork(SaftNetwork&&) noexcept = default;
SaftNetwork& SaftNetwork::operator=(SaftNetwork&&) noexcept = default;

SaftNetwork SaftNetwork::load(const std::filesystem::path& file, SaftNetworkOptions options) {
  SaftNetwork n(options);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open the SAFT weights file");
  char magic[8];
  std::uint32_t header[3];
  in.read(magic, sizeof magic);
  in.read(reinterpret_cast<char*>(header), sizeof header);
  if (!in || std::memcmp(magic, kWeightsMagic, sizeof magic) != 0)
    throw InputError(file.string() + ": not a SAFT weights file (bad magic)");
  if (header[0] != kWeightsVersion) throw InputError(file.string() + ": SAFT weights version " + std::to_string(header[0]) + ", expected 1");
  if (header[1] != static_cast<std::uint32_t>(kDimension))
    throw InputError(file.string() + ": SAFT weights of dimension " + std::to_string(header[1]) + ", this build expects " +
                     std::to_string(kDimension));
  torch::NoGradGuard no_grad;
  auto tensors = stored_tensors(n.impl_->net);
  if (header[2] != tensors.size())
    throw InputError(file.string() + ": " + std::to_string(header[2]) + " tensors, the network has " + std::to_string(tensors.size()));
  for (std::size_t i = 0; i < tensors.size(); ++i) {
    std::uint32_t count = 0;
    in.read(reinterpret_cast<char*>(&count), sizeof count);
    if (!in) throw InputError(file.string() + ": truncated at tensor " + std::to_string(i));
    if (count != static_cast<std::uint32_t>(tensors[i].numel()))
      throw InputError(file.string() + ": tensor " + std::to_string(i) + " has " + std::to_string(count) + " values, expected " +
                       std::to_string(tensors[i].numel()));
    std::vector<float> values(count);
    in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(count * sizeof(float)));
    if (!in) throw InputError(file.string() + ": truncated in tensor " + std::to_string(i));
    for (float v : values)
      if (!std::isfinite(v)) throw InputError(file.string() + ": tensor " + std::to_string(i) + " holds a non-finite value");
    tensors[i].copy_(torch::from_blob(values.data(), tensors[i].sizes(), torch::kFloat32));
  }
  if (in.peek() != std::char_traits<char>::eof()) throw InputError(file.string() + ": trailing bytes after the last tensor");
  n.impl_->net->eval();
  n.warm_up();
  return n;
}

void SaftNetwork::save(const std::filesystem::path& file) const {
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary);
  if (!out) throw InputError(file.string() + ": cannot write the SAFT weights file");
  auto tensors = stored_tensors(impl_->net);
  const std::uint32_t header[3] = {kWeightsVersion, static_cast<std::uint32_t>(kDimension), static_cast<std::uint32_t>(tensors.size())};
  out.write(kWeightsMagic, sizeof kWeightsMagic);
  out.write(reinterpret_cast<const char*>(header), sizeof header);
  for (auto& t : tensors) {
    const torch::Tensor c = t.detach().to(torch::kFloat32).contiguous();
    const auto count = static_cast<std::uint32_t>(c.numel());
    out.write(reinterpret_cast<const char*>(&count), sizeof count);
    out.write(reinterpret_cast<const char*>(c.data_ptr<float>()), static_cast<std::streamsize>(count * sizeof(float)));
  }
  if (!out) throw Failure(file.string() + ": write failed");
}

void SaftNetwork::describe(const cv::Mat& patches, cv::Mat& unit, cv::Mat* raw) {
  CV_Assert(patches.type() == CV_32FC1 && patches.cols == kSaftPatchPixels && patches.isContinuous());
  const int n = patches.rows, b = options_.batch_size;
  unit.create(n, kDimension, CV_32F);
  if (raw) raw->create(n, kDimension, CV_32F);
  torch::set_num_threads(options_.threads);
  c10::InferenceMode guard;
  impl_->net->eval();
  // Every forward pass has the same shape: the last batch is padded with zeros.
  torch::Tensor input = torch::zeros({b, 1, kSaftPatchSize, kSaftPatchSize});
  for (int start = 0; start < n; start += b) {
    const int m = std::min(b, n - start);
    std::memcpy(input.data_ptr<float>(), patches.ptr<float>(start), static_cast<std::size_t>(m) * kSaftPatchPixels * sizeof(float));
    if (m < b) input.narrow(0, m, b - m).zero_();
    const torch::Tensor out = impl_->net->forward(input).narrow(0, 0, m).contiguous();
    const torch::Tensor normalized = torch::nn::functional::normalize(
        out, torch::nn::functional::NormalizeFuncOptions().p(2).dim(1).eps(1e-12)).contiguous();
    std::memcpy(unit.ptr<float>(start), normalized.data_ptr<float>(), static_cast<std::size_t>(m) * kDimension * sizeof(float));
    if (raw) std::memcpy(raw->ptr<float>(start), out.data_ptr<float>(), static_cast<std::size_t>(m) * kDimension * sizeof(float));
  }
}

void SaftNetwork::warm_up() {
  // The first forward pass allocates and picks kernels; doing it here keeps that cost out
  // of the first frame.
  cv::Mat zeros = cv::Mat::zeros(1, kSaftPatchPixels, CV_32F), unit;
  describe(zeros, unit);
}

long SaftNetwork::multiply_adds_per_patch() {
  long total = 0;
  for (const auto& c : saft_detail::kConvs) total += static_cast<long>(c.out_size) * c.out_size * c.out * c.in * 9;
  return total + static_cast<long>(saft_detail::kFlat) * kDimension;
}

long SaftNetwork::parameter_count() const {
  long total = 0;
  for (auto& t : stored_tensors(impl_->net)) total += t.numel();
  return total;
}

std::vector<float> SaftNetwork::weights() const {
  std::vector<float> out;
  out.reserve(static_cast<std::size_t>(parameter_count()));
  for (auto& t : stored_tensors(impl_->net)) {
    const torch::Tensor c = t.detach().contiguous();
    out.insert(out.end(), c.data_ptr<float>(), c.data_ptr<float>() + c.numel());
  }
  return out;
}

void SaftNetwork::set_weights(const std::vector<float>& values) {
  if (static_cast<long>(values.size()) != parameter_count())
    throw std::invalid_argument("SAFT weights: " + std::to_string(values.size()) + " values, the network has " +
                                std::to_string(parameter_count()));
  torch::NoGradGuard no_grad;
  std::size_t at = 0;
  for (auto& t : stored_tensors(impl_->net)) {
    t.copy_(torch::from_blob(const_cast<float*>(values.data() + at), t.sizes(), torch::kFloat32));
    at += static_cast<std::size_t>(t.numel());
  }
}

std::filesystem::path SaftNetwork::default_weights_path() { return BUILTSCENE_SAFT_WEIGHTS; }

}  // namespace builtscene
