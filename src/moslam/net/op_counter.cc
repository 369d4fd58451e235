#include "moslam/net/op_counter.h"

#include <chrono>
#include <cstring>
#include <memory>

#include <ATen/core/ivalue.h>
#include <ATen/record_function.h>

#include "moslam/net/fused_pointwise.h"
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

// What the start callback reads from the inputs (valid only there: an operator's inputs may be
// gone by its end) for the end callback, which multiplies it by the output's size.
struct OpContext : at::ObserverContext {
  bool counted = false;
  OpKind kind = OpKind::kGemm;
  double macs_per_output = 0.0;
  Clock::time_point start;
};

bool IsCounted(const char* name) {
  return std::strcmp(name, "aten::conv2d") == 0 || std::strcmp(name, "aten::addmm") == 0 ||
         std::strcmp(name, "aten::mm") == 0 || std::strcmp(name, kFusedPointwiseOp) == 0;
}

const at::Tensor* TensorAt(c10::ArrayRef<const c10::IValue> inputs, size_t i, int64_t dim) {
  if (inputs.size() <= i || !inputs[i].isTensor()) return nullptr;
  const at::Tensor& t = inputs[i].toTensor();
  return t.dim() == dim ? &t : nullptr;
}

// The kind and the multiply-adds per output element of an operator from its inputs; false when
// they are not the tensors expected (then it is not counted).
bool Classify(const at::RecordFunction& fn, OpContext* context) {
  const auto inputs = fn.inputs();
  if (std::strcmp(fn.name(), "aten::conv2d") == 0) {
    const at::Tensor* x = TensorAt(inputs, 0, 4);
    const at::Tensor* w = TensorAt(inputs, 1, 4);  // {out, in / groups, kh, kw}
    if (x == nullptr || w == nullptr) return false;
    context->macs_per_output = static_cast<double>(w->size(1) * w->size(2) * w->size(3));
    context->kind = OpKind::kDenseConv;
    if (w->size(1) == 1 && x->size(1) > 1 && w->size(0) % x->size(1) == 0) {
      context->kind = OpKind::kDepthwise;
    } else if (w->size(2) == 1 && w->size(3) == 1) {
      context->kind = OpKind::kPointwise;
    }
    return true;
  }
  if (std::strcmp(fn.name(), kFusedPointwiseOp) == 0) {  // inputs x, weights {out, in}
    const at::Tensor* w = TensorAt(inputs, 1, 2);
    if (w == nullptr) return false;
    context->kind = OpKind::kPointwise;
    context->macs_per_output = static_cast<double>(w->size(1));
    return true;
  }
  // addmm(bias, a, b) and mm(a, b): a is {m, k}, the output {m, n}.
  const at::Tensor* a = TensorAt(inputs, std::strcmp(fn.name(), "aten::addmm") == 0 ? 1 : 0, 2);
  if (a == nullptr) return false;
  context->kind = OpKind::kGemm;
  context->macs_per_output = static_cast<double>(a->size(1));
  return true;
}

std::unique_ptr<at::ObserverContext> OnStart(const at::RecordFunction& fn) {
  auto context = std::make_unique<OpContext>();
  if (tls.count != nullptr && tls.depth == 0 && IsCounted(fn.name()) &&
      Classify(fn, context.get())) {
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
  const auto& outputs = fn.outputs();
  if (tls.count == nullptr || outputs.empty() || !outputs[0].isTensor()) return;
  OpStats& stats = tls.count->by_kind[context->kind];
  ++stats.calls;
  stats.macs += static_cast<double>(outputs[0].toTensor().numel()) * context->macs_per_output;
  stats.ms += ms;
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
