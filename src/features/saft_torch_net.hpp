#pragma once
// Private to saft_network.cpp and saft_trainer.cpp (the only translation units that include
// torch): the libtorch module behind SaftNetwork.
#include <torch/torch.h>

#include "features/saft_network.hpp"

namespace builtscene::saft_detail {

// Layer table shared by the module and by SaftNetwork::multiply_adds_per_patch().
struct ConvSpec {
  int in, out, stride, out_size;  // out_size: output width = height
};
inline constexpr ConvSpec kConvs[] = {{1, 8, 1, 32}, {8, 16, 2, 16}, {16, 32, 2, 8}, {32, 64, 2, 4}};
inline constexpr int kFlat = 64 * 4 * 4;

struct SaftNetImpl : torch::nn::Module {
  explicit SaftNetImpl(int dimension) {
    for (int i = 0; i < 4; ++i) {
      const ConvSpec& c = kConvs[i];
      // No conv bias: the batch norm that follows has its own shift.
      convs.push_back(register_module("conv" + std::to_string(i + 1),
                                      torch::nn::Conv2d(torch::nn::Conv2dOptions(c.in, c.out, 3).stride(c.stride).padding(1).bias(false))));
      norms.push_back(register_module("bn" + std::to_string(i + 1), torch::nn::BatchNorm2d(c.out)));
    }
    fc = register_module("fc", torch::nn::Linear(kFlat, dimension));
  }
  // x: [B, 1, 32, 32] -> [B, dimension], not normalized.
  torch::Tensor forward(torch::Tensor x) {
    for (std::size_t i = 0; i < convs.size(); ++i) x = torch::relu(norms[i]->forward(convs[i]->forward(x)));
    return fc->forward(x.flatten(1));
  }
  std::vector<torch::nn::Conv2d> convs;
  std::vector<torch::nn::BatchNorm2d> norms;
  torch::nn::Linear fc{nullptr};
};
TORCH_MODULE(SaftNet);

}  // namespace builtscene::saft_detail

namespace builtscene {

struct SaftNetwork::Impl {
  explicit Impl(unsigned seed) : net(nullptr) {
    torch::manual_seed(seed);
    net = saft_detail::SaftNet(SaftNetwork::kDimension);
    net->eval();
  }
  saft_detail::SaftNet net;
};

}  // namespace builtscene
