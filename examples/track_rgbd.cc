// Tracks a TUM RGB-D folder (e.g. from `moslam synth`) with the installed moslam library and
// writes the camera trajectory: usage track_rgbd SEQUENCE SETTINGS VOCABULARY|none [OUT.txt]
#include <iostream>

#include <opencv2/imgcodecs.hpp>

#include <moslam/io/dataset.h>
#include <moslam/moslam.h>

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: track_rgbd SEQUENCE SETTINGS VOCABULARY|none [OUT.txt]\n";
    return 2;
  }
  try {
    const moslam::io::Sequence sequence = moslam::io::ReadDataset(argv[1]);
    moslam::api::SlamOptions options;
    options.settings = argv[2];
    options.vocabulary = std::string(argv[3]) == "none" ? "" : argv[3];
    options.sensor = moslam::api::Sensor::kRgbD;
    moslam::api::Slam slam(options);
    int tracked = 0;
    for (const moslam::io::FrameEntry& frame : sequence.frames) {
      const cv::Mat image = cv::imread(frame.image_left, cv::IMREAD_COLOR);
      const cv::Mat depth = cv::imread(frame.depth, cv::IMREAD_UNCHANGED);
      const moslam::api::Tracked t = slam.TrackRgbD(frame.timestamp, image, depth);
      if (t.T_world_cam) ++tracked;
    }
    slam.Finish();
    moslam::eval::WriteTum(slam.Trajectory(), argc > 4 ? argv[4] : "trajectory.txt");
    std::cout << tracked << " of " << sequence.size() << " frames tracked, "
              << slam.MapPoints().size() << " map points\n";
    return tracked > 0 ? 0 : 1;
  } catch (const moslam::InputError& e) {
    std::cerr << "track_rgbd: " << e.what() << "\n";
    return 1;
  }
}
