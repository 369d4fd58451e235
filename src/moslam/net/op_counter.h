// The arithmetic of a network and where its time goes: multiply-adds and wall time of each
// convolution and matrix product libtorch runs on this thread, grouped by kind, read from
// libtorch's own operator dispatch (at::RecordFunction) rather than from a hand-kept list of
// layers, so that it counts what actually runs (the 1x1 convolutions that mobilenet_v2.cc sends
// to a GEMM as well as those that stay convolutions).
//
// What the issue on real time asks for: the shipped networks' multiply-adds per frame and the
// GFLOP/s each kind of layer reaches, beside the machine's peak (bench_net_throughput).
#pragma once

#include <cstdint>
#include <map>
#include <string>

namespace moslam::net {

// Kinds of counted operators. A convolution's kind is read from its weight: 1x1 (pointwise),
// one input channel per group and as many groups as input channels (depthwise), or any other
// (dense, e.g. the 3x3 stem and the ASPP branches); FusedPointwise (fused_pointwise.h) is
// pointwise. aten::addmm / aten::mm are GEMMs: in these networks the pointwise convolutions
// that training runs (mobilenet_v2.cc's Pointwise) and nothing else.
enum class OpKind { kPointwise, kDepthwise, kDenseConv, kGemm };
const char* ToString(OpKind kind);

struct OpStats {
  int64_t calls = 0;
  double macs = 0.0;  // multiply-adds (one FMA each); FLOPs are twice this
  double ms = 0.0;    // wall time between the operator's entry and exit

  // Giga floating-point operations per second: 2 x multiply-adds / time; 0 without time.
  double Gflops() const { return ms > 0.0 ? 2.0 * macs / (ms * 1e6) : 0.0; }
};

struct OpCount {
  std::map<OpKind, OpStats> by_kind;
  OpStats Total() const;  // the counted operators together (not the copies between them)
};

// Counts, while it lives, the convolutions and GEMMs dispatched on the thread that made it (a
// thread-local at::RecordFunction callback; libtorch's intra-op workers are not listened to, the
// operator's wall time on this thread covers them). An operator inside a counted one (the GEMM
// of an im2col convolution) is not counted again. One counter per thread at a time (CHECK).
class OpCounter {
 public:
  OpCounter();
  ~OpCounter();
  OpCounter(const OpCounter&) = delete;
  OpCounter& operator=(const OpCounter&) = delete;

  const OpCount& count() const { return count_; }
  void Reset() { count_ = OpCount(); }

 private:
  OpCount count_;
  uint64_t handle_ = 0;
};

}  // namespace moslam::net
