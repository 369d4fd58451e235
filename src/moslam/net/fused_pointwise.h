// The 1x1 convolutions of the networks at inference, each as one oneDNN matmul primitive with
// the bias and the activation fused into it.
//
// Why: the 1x1 convolutions are 73 % of the shipped networks' multiply-adds, and as a libtorch
// GEMM (OpenBLAS's sgemm, mobilenet_v2.cc's Pointwise) followed by a bias and an activation pass
// each they reached 43 % of the machine's peak (bench_net_throughput). oneDNN (Intel; the
// library libtorch itself links for its convolutions, Debian's libdnnl) chooses its kernels at
// run time from the CPU's instruction sets (AVX2, AVX-512), so it does not depend on OpenBLAS
// recognising the CPU's model, and it applies the bias and the activation to each block of the
// product while that block is still in cache instead of in two more passes over memory.
#pragma once

#include <torch/torch.h>

namespace moslam::net {

enum class Activation { kNone, kRelu, kRelu6 };

// The operator's name to at::RecordFunction (profilers, OpCounter): inputs x (NHWC) and the
// weights as {O, I}, output {N, O, H, W}.
inline constexpr char kFusedPointwiseOp[] = "moslam::fused_pointwise";

// Whether FusedPointwise can run a 1x1 convolution (weight {O, I, 1, 1}, bias {O}) on x: float
// tensors on the CPU, 4-D x with I channels, and no gradient wanted (autograd does not see
// through oneDNN; training keeps libtorch's operators).
bool FusedPointwiseApplies(const torch::Tensor& x, const torch::Tensor& weight,
                           const torch::Tensor& bias);

// activation(conv1x1(x, weight) + bias) as one matmul over x's NHWC rows: x {N, I, H, W} (any
// memory format; channels-last is read in place), weight {O, I, 1, 1} contiguous or channels-
// last, bias {O}. Returns {N, O, H, W} in channels-last memory. Runs on libtorch's intra-op
// thread count (oneDNN and libtorch share the OpenMP runtime). CHECKs FusedPointwiseApplies.
torch::Tensor FusedPointwise(const torch::Tensor& x, const torch::Tensor& weight,
                             const torch::Tensor& bias, Activation activation);

}  // namespace moslam::net
