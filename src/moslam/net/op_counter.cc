#include "moslam/net/op_counter.h"

#include <chrono>
#include <cstring>
#include <memory>
#include <optional>

#include <ATen/core/ivalue.h>
#include <ATen/record_function.h>

#include "moslam/util/check.h"

namespace moslam::net {
namespace {

using Clock = std::chrono::steady_clock;

// RecordFunction callbacks are plain function pointers: the counter they add to is found through
// this thread's pointer, set while an OpCounter lives on the thread.
struct ThreadState {
  OpCount* count = nullptr;
  int depth = 0;  // counted operators open on this thread (nested ones are not counted again)
};
thread_local ThreadState tls;

struct OpContext : at::ObserverContext {
  bool counted = false;
  Clock::time_point start;
};

bool IsCounted(const char* name) {
  return std::strcmp(name, "aten::conv2d") == 0 || std::strcmp(name, "aten::addmm") == 0 ||
         std::strcmp(name, "aten::mm") == 0;
}

// The kind and multiply-adds of a finished operator from its inputs and output; nullopt when its
// arguments are not the tensors expected (then it is not counted).
std::optional<std::pair<OpKind, double>> Measure(const at::RecordFunction& fn) {
  const auto inputs = fn.inputs();
  const auto& outputs = fn.outputs();
  if (outputs.empty() || !outputs[0].isTensor()) return std::nullopt;
  const at::Tensor& out = outputs[0].toTensor();
  if (std::strcmp(fn.name(), "aten::conv2d") == 0) {
    if (inputs.size() < 2 || !inputs[0].isTensor() || !inputs[1].isTensor()) return std::nullopt;
    const at::Tensor& x = inputs[0].toTensor();
    const at::Tensor& w = inputs[1].toTensor();  // {out, in / groups, kh, kw}
    if (w.dim() != 4 || x.dim() != 4) return std::nullopt;
    const double per_output = static_cast<double>(w.size(1) * w.size(2) * w.size(3));
    OpKind kind = OpKind::kDenseConv;
    if (w.size(1) == 1 && x.size(1) > 1 && w.size(0) % x.size(1) == 0) {
      kind = OpKind::kDepthwise;
    } else if (w.size(2) == 1 && w.size(3) == 1) {
      kind = OpKind::kPointwise;
    }
    return std::make_pair(kind, static_cast<double>(out.numel()) * per_output);
  }
  // addmm(bias, a, b) and mm(a, b): a is {m, k}, the output {m, n}.
  const size_t a = std::strcmp(fn.name(), "aten::addmm") == 0 ? 1 : 0;
  if (inputs.size() <= a || !inputs[a].isTensor()) return std::nullopt;
  const at::Tensor& lhs = inputs[a].toTensor();
  if (lhs.dim() != 2) return std::nullopt;
  return std::make_pair(OpKind::kGemm, static_cast<double>(out.numel()) * lhs.size(1));
}

std::unique_ptr<at::ObserverContext> OnStart(const at::RecordFunction& fn) {
  auto context = std::make_unique<OpContext>();
  if (tls.count != nullptr && tls.depth == 0 && IsCounted(fn.name())) {
    context->counted = true;
    ++tls.depth;
    context->start = Clock::now();
  }
  return context;
}

void OnEnd(const at::RecordFunction& fn, at::ObserverContext* base) {
  auto* context = static_cast<OpContext*>(base);
  if (context == nullptr || !context->counted) return;
  const double ms =
      std::chrono::duration<double, std::milli>(Clock::now() - context->start).count();
  --tls.depth;
  if (tls.count == nullptr) return;
  if (const auto measured = Measure(fn)) {
    OpStats& stats = tls.count->by_kind[measured->first];
    ++stats.calls;
    stats.macs += measured->second;
    stats.ms += ms;
  }
}

}  // namespace

const char* ToString(OpKind kind) {
  switch (kind) {
    case OpKind::kPointwise:
      return "pointwise";
    case OpKind::kDepthwise:
      return "depthwise";
    case OpKind::kDenseConv:
      return "dense_conv";
    case OpKind::kGemm:
      return "gemm";
  }
  return "unknown";
}

OpStats OpCount::Total() const {
  OpStats total;
  for (const auto& [kind, stats] : by_kind) {
    total.calls += stats.calls;
    total.macs += stats.macs;
    total.ms += stats.ms;
  }
  return total;
}

OpCounter::OpCounter() {
  MOSLAM_CHECK(tls.count == nullptr);  // one counter per thread at a time
  tls.count = &count_;
  tls.depth = 0;
  handle_ = at::addThreadLocalCallback(at::RecordFunctionCallback(&OnStart, &OnEnd)
                                           .needsInputs(true)
                                           .needsOutputs(true)
                                           .scopes({at::RecordScope::FUNCTION}));
}

OpCounter::~OpCounter() {
  at::removeCallback(handle_);
  tls.count = nullptr;
  tls.depth = 0;
}

}  // namespace moslam::net
