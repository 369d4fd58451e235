#include "moslam/net/fused_pointwise.h"

#include <vector>

#include <ATen/Parallel.h>
#include <ATen/record_function.h>
#include <oneapi/dnnl/dnnl.hpp>

#include "moslam/util/check.h"

namespace moslam::net {
namespace {

// One CPU engine per process; a stream per thread (a oneDNN stream is not meant to be shared
// between threads that execute at once).
const dnnl::engine& Engine() {
  static const dnnl::engine engine(dnnl::engine::kind::cpu, 0);
  return engine;
}

dnnl::stream& Stream() {
  thread_local dnnl::stream stream(Engine());
  return stream;
}

// Row-major {rows, cols} with a leading dimension: the matmul's plain layouts.
dnnl::memory::desc Matrix(int64_t rows, int64_t cols, int64_t row_stride, int64_t col_stride) {
  return dnnl::memory::desc({rows, cols}, dnnl::memory::data_type::f32,
                            dnnl::memory::dims{row_stride, col_stride});
}

}  // namespace

bool FusedPointwiseApplies(const torch::Tensor& x, const torch::Tensor& weight,
                           const torch::Tensor& bias) {
  const bool grad = torch::GradMode::is_enabled() &&
                    (x.requires_grad() || weight.requires_grad() || bias.requires_grad());
  return !grad && x.dim() == 4 && weight.dim() == 4 && bias.dim() == 1 && x.is_cpu() &&
         weight.is_cpu() && bias.is_cpu() && x.scalar_type() == torch::kFloat &&
         weight.scalar_type() == torch::kFloat && bias.scalar_type() == torch::kFloat &&
         weight.size(2) == 1 && weight.size(3) == 1 && weight.size(1) == x.size(1) &&
         bias.size(0) == weight.size(0);
}

torch::Tensor FusedPointwise(const torch::Tensor& x, const torch::Tensor& weight,
                             const torch::Tensor& bias, Activation activation) {
  MOSLAM_CHECK(FusedPointwiseApplies(x, weight, bias));
  const int64_t n = x.size(0), c = x.size(1), h = x.size(2), w = x.size(3);
  const int64_t out = weight.size(0);
  const int64_t rows = n * h * w;
  const torch::Tensor src = x.contiguous(torch::MemoryFormat::ChannelsLast);  // {rows, c}
  // {out, c} row-major: a contiguous or channels-last 1x1 weight has this memory either way.
  const torch::Tensor weights = weight.reshape({out, c}).contiguous();
  const torch::Tensor b = bias.contiguous();
  torch::Tensor dst =
      torch::empty({n, out, h, w}, x.options().memory_format(torch::MemoryFormat::ChannelsLast));
  if (rows == 0) return dst;

  // dst {rows, out} = src {rows, c} x weights^T {c, out} + bias {1, out}, then the activation.
  const dnnl::memory::desc src_md = Matrix(rows, c, c, 1);
  const dnnl::memory::desc weights_md = Matrix(c, out, 1, c);  // the transpose, by strides
  const dnnl::memory::desc bias_md = Matrix(1, out, out, 1);
  const dnnl::memory::desc dst_md = Matrix(rows, out, out, 1);
  dnnl::post_ops post_ops;
  if (activation == Activation::kRelu) {
    post_ops.append_eltwise(1.0f, dnnl::algorithm::eltwise_relu, 0.0f, 0.0f);
  } else if (activation == Activation::kRelu6) {
    post_ops.append_eltwise(1.0f, dnnl::algorithm::eltwise_clip, 0.0f, 6.0f);
  }
  dnnl::primitive_attr attr;
  attr.set_post_ops(post_ops);
  // oneDNN's primitive cache makes the repeated creation for a shape a lookup.
  const dnnl::matmul::primitive_desc pd(dnnl::matmul::desc(src_md, weights_md, bias_md, dst_md),
                                        attr, Engine());
  const dnnl::matmul matmul(pd);
  // oneDNN runs on the calling thread's OpenMP thread count: the one libtorch sets for its own
  // operators on this thread (at::set_num_threads), initialised here if none ran on it yet.
  at::internal::lazy_init_num_threads();
  // One operator to libtorch's profiler and to OpCounter (op_counter.h), as aten::addmm was.
  RECORD_FUNCTION(kFusedPointwiseOp, std::vector<c10::IValue>({src, weights}));
  dnnl::stream& stream = Stream();
  matmul.execute(
      stream,
      {{DNNL_ARG_SRC, dnnl::memory(src_md, Engine(), const_cast<float*>(src.data_ptr<float>()))},
       {DNNL_ARG_WEIGHTS,
        dnnl::memory(weights_md, Engine(), const_cast<float*>(weights.data_ptr<float>()))},
       {DNNL_ARG_BIAS, dnnl::memory(bias_md, Engine(), const_cast<float*>(b.data_ptr<float>()))},
       {DNNL_ARG_DST, dnnl::memory(dst_md, Engine(), dst.data_ptr<float>())}});
  stream.wait();
  if (guard.isActive() && guard.needsOutputs()) guard.setOutputs(std::vector<c10::IValue>{dst});
  return dst;
}

}  // namespace moslam::net
