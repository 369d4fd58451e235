// Test support: a runner::Tracker whose View() is a map of a given size, for the live viewer's
// tests and benchmark (no SLAM core needed).
#pragma once

#include <atomic>

#include "moslam/runner/tracker.h"

namespace moslam::viewer::testing {

class FakeTracker : public runner::Tracker {
 public:
  FakeTracker(size_t points, size_t keyframes, size_t keypoints) {
    for (size_t i = 0; i < points; ++i) {
      view_.points.insert(view_.points.end(), {0.01f * i, 0.02f * (i % 7), 1.0f + 0.001f * i});
      view_.point_states.push_back(static_cast<uint8_t>(i % 6));
    }
    view_.keyframes.assign(keyframes, geometry::SE3());
    for (size_t i = 0; i < keypoints; ++i) {
      view_.keypoints.insert(view_.keypoints.end(), {1.0f * (i % 640), 1.0f * (i % 480)});
      view_.keypoint_kinds.push_back(static_cast<uint8_t>(i % 4));
    }
    // A tenth as many taken by the mask, and one closed loop between the first and the last
    // keyframe.
    for (size_t i = 0; i < keypoints / 10; ++i) {
      view_.rejected_keypoints.insert(view_.rejected_keypoints.end(), {10.0f + i, 20.0f});
    }
    if (keyframes >= 2) view_.loops = {0, static_cast<uint32_t>(keyframes - 1)};
  }
  slam::FrameReport Track(const slam::FrameInput&) override { return {}; }
  void Finish() override {}
  eval::Trajectory CameraTrajectory() const override { return {}; }
  eval::Trajectory KeyFrameTrajectory() const override { return {}; }
  slam::MapSummary Summary() const override { return {}; }
  bool View(slam::SystemView* view, const slam::ViewRequest& request) override {
    ++views;
    *view = view_;
    if (!watched) view->rejected_keypoints.clear();  // as System: only while watched
    // A chain of keyframes with its neighbours, as a spanning tree and a covisibility graph.
    if (request.graph) {
      view->has_graph = true;
      for (uint32_t i = 1; i < view_.keyframes.size(); ++i) {
        view->spanning_tree.insert(view->spanning_tree.end(), {i, i - 1});
        view->covisibility.insert(view->covisibility.end(), {i, i - 1, 150, i - 1, i, 150});
      }
    }
    return true;
  }
  void Watch(bool on) override { watched = on; }
  // How many points View() reports as in the map (not erased).
  size_t MapPoints() const {
    size_t n = 0;
    for (uint8_t s : view_.point_states) n += s < 4 ? 1 : 0;
    return n;
  }
  std::atomic<int> views{0};
  bool watched = false;  // the last Watch()

 private:
  slam::SystemView view_;
};

}  // namespace moslam::viewer::testing
