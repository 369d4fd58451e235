// Which BLAS libtorch's matrix products reach in an executable linked like `moslam` (libtorch
// and Ceres, whose SuiteSparse dependency brings BLAS and LAPACK onto the link line). The
// symbol lookup takes the first library in load order that defines sgemm_; when ATLAS's
// libf77blas is a direct dependency of the executable it wins over libblas.so.3, the one
// Debian's alternatives point at OpenBLAS, and the networks run 2.5x slower (CMakeLists.txt
// keeps ATLAS off the link line).
#include <dlfcn.h>

#include <string>

#include <ceres/version.h>
#include <gtest/gtest.h>
#include <torch/torch.h>

namespace moslam::net {
namespace {

TEST(Blas, SgemmComesFromTheAlternativesBlasNotFromAtlasF77Interface) {
  // A matrix product first, so that libtorch has bound its BLAS.
  const torch::Tensor a = torch::ones({64, 64});
  EXPECT_FLOAT_EQ(torch::mm(a, a)[0][0].item<float>(), 64.0f);
  void* sgemm = dlsym(RTLD_DEFAULT, "sgemm_");
  ASSERT_NE(sgemm, nullptr) << "no sgemm_ in the process";
  Dl_info info{};
  ASSERT_NE(dladdr(sgemm, &info), 0);
  const std::string library = info.dli_fname;
  EXPECT_EQ(library.find("f77blas"), std::string::npos)
      << "sgemm_ resolves to " << library << " (Ceres " << CERES_VERSION_STRING
      << "'s BLAS on the link line): see the filter of Ceres::ceres's link interface and "
         "BLA_VENDOR in CMakeLists.txt";
}

}  // namespace
}  // namespace moslam::net
