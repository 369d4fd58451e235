#include "moslam/synth/check.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/geometry/se3.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/synth/scene.h"
#include "moslam/util/error.h"

namespace moslam::synth {
namespace {

struct Frame {
  std::string stamp;
  geometry::SE3 T_world_cam;
};

std::vector<Frame> ReadGroundTruth(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw InputError("cannot read " + path);
  std::vector<Frame> frames;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    Frame fr;
    double v[7];
    s >> fr.stamp;
    for (double& x : v) s >> x;
    if (!s) throw InputError("malformed line in " + path + ": " + line);
    fr.T_world_cam = geometry::SE3(Eigen::Quaterniond(v[6], v[3], v[4], v[5]).normalized(),
                                   Eigen::Vector3d(v[0], v[1], v[2]));
    frames.push_back(fr);
  }
  return frames;
}

cv::Mat Load(const std::string& path, int flags) {
  cv::Mat m = cv::imread(path, flags);
  if (m.empty()) throw InputError("cannot read " + path);
  return m;
}

double Percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

ReprojectionStats CheckReprojection(const std::string& dir, int gap, int step, int pixel_step) {
  const std::vector<Frame> frames = ReadGroundTruth(dir + "/groundtruth.txt");
  const io::OrbSlamSettings settings =
      io::LoadOrbSlamSettings(dir + "/settings.yaml", io::SensorType::kRgbD);
  const auto& c = settings.camera;
  std::vector<double> dz, dg;
  ReprojectionStats st;
  // depth_gt/ (exact depth) when the sequence was written with it, else the noisy depth/.
  namespace fs = std::filesystem;
  const char* exact_dir = fs::is_directory(fs::path(dir) / "depth_gt") ? "depth_gt" : "depth";
  st.exact_depth = exact_dir == std::string("depth_gt");
  long noisy_ok = 0, noisy_n = 0;
  for (size_t i = 0; i + static_cast<size_t>(gap) < frames.size(); i += static_cast<size_t>(step)) {
    const Frame& a = frames[i];
    const Frame& b = frames[i + static_cast<size_t>(gap)];
    const auto path = [&](const char* sub, const Frame& f) {
      return dir + "/" + sub + "/" + f.stamp + ".png";
    };
    const cv::Mat za = Load(path(exact_dir, a), cv::IMREAD_UNCHANGED);
    const cv::Mat zb = Load(path(exact_dir, b), cv::IMREAD_UNCHANGED);
    const cv::Mat nb = Load(path("depth", b), cv::IMREAD_UNCHANGED);
    const cv::Mat ca = Load(path("class", a), cv::IMREAD_UNCHANGED);
    const cv::Mat cb = Load(path("class", b), cv::IMREAD_UNCHANGED);
    cv::Mat ga, gb;
    cv::cvtColor(Load(path("rgb", a), cv::IMREAD_COLOR), ga, cv::COLOR_BGR2GRAY);
    cv::cvtColor(Load(path("rgb", b), cv::IMREAD_COLOR), gb, cv::COLOR_BGR2GRAY);
    const geometry::SE3 T_b_a = b.T_world_cam.Inverse() * a.T_world_cam;
    for (int v = 0; v < za.rows; v += pixel_step) {
      for (int u = 0; u < za.cols; u += pixel_step) {
        const double z = za.at<uint16_t>(v, u) / 5000.0;
        if (z <= 0 || IsMovableClass(ca.at<uint8_t>(v, u))) continue;
        const Eigen::Vector3d pa((u - c.cx) * z / c.fx, (v - c.cy) * z / c.fy, z);
        const Eigen::Vector3d pb = T_b_a * pa;
        if (pb.z() <= 0.1) continue;
        const double ub = c.fx * pb.x() / pb.z() + c.cx, vb = c.fy * pb.y() / pb.z() + c.cy;
        const int u0 = static_cast<int>(std::floor(ub)), v0 = static_cast<int>(std::floor(vb));
        if (u0 < 0 || v0 < 0 || u0 + 1 >= za.cols || v0 + 1 >= za.rows) continue;
        // Bilinear depth over a 2x2 neighbourhood of one static surface (no depth edge).
        double d[4];
        bool ok = true;
        for (int k = 0; k < 4; ++k) {
          const int x = u0 + (k & 1), y = v0 + (k >> 1);
          d[k] = zb.at<uint16_t>(y, x) / 5000.0;
          if (d[k] <= 0 || IsMovableClass(cb.at<uint8_t>(y, x))) ok = false;
        }
        if (!ok) continue;
        const double lo = *std::min_element(d, d + 4), hi = *std::max_element(d, d + 4);
        if (hi - lo > 0.02 * lo) continue;  // depth edge
        const double fu = ub - u0, fv = vb - v0;
        const double zi =
            (1 - fv) * ((1 - fu) * d[0] + fu * d[1]) + fv * ((1 - fu) * d[2] + fu * d[3]);
        ++st.checked;
        if (pb.z() > zi + 0.05) {
          ++st.occluded;
          continue;
        }
        dz.push_back(std::abs(pb.z() - zi));
        const double gi =
            (1 - fv) * ((1 - fu) * gb.at<uint8_t>(v0, u0) + fu * gb.at<uint8_t>(v0, u0 + 1)) +
            fv * ((1 - fu) * gb.at<uint8_t>(v0 + 1, u0) + fu * gb.at<uint8_t>(v0 + 1, u0 + 1));
        dg.push_back(std::abs(gi - ga.at<uint8_t>(v, u)));
        const int un = static_cast<int>(std::lround(ub)), vn = static_cast<int>(std::lround(vb));
        const double zn = nb.at<uint16_t>(vn, un) / 5000.0;
        if (zn > 0) {
          const double sigma = 0.0012 + 0.0019 * (pb.z() - 0.4) * (pb.z() - 0.4);
          const double quant = pb.z() * pb.z() / settings.bf / 8.0;
          ++noisy_n;
          if (std::abs(zn - pb.z()) <= 3 * sigma + quant + 0.002) ++noisy_ok;
        }
      }
    }
  }
  st.depth_median = Percentile(dz, 0.5);
  st.depth_p90 = Percentile(dz, 0.9);
  st.depth_p99 = Percentile(dz, 0.99);
  st.grey_median = Percentile(dg, 0.5);
  st.grey_p90 = Percentile(dg, 0.9);
  st.noisy_within_3sigma = noisy_n ? static_cast<double>(noisy_ok) / noisy_n : 0.0;
  return st;
}

}  // namespace moslam::synth
