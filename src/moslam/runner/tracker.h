// What the run loop drives: anything that takes frames and gives per-frame reports and, at the
// end, trajectories. slam::System is adapted to it by the `moslam run` command; tests use fakes,
// so this module needs only slam's value types (slam/system.h, header only), not the SLAM core.
#pragma once

#include "moslam/eval/trajectory.h"
#include "moslam/slam/system.h"

namespace moslam::runner {

class Tracker {
 public:
  virtual ~Tracker() = default;
  virtual slam::FrameReport Track(const slam::FrameInput& input) = 0;
  // Called once after the last frame: drain background work (local mapping), stop threads.
  virtual void Finish() = 0;
  virtual eval::Trajectory CameraTrajectory() const = 0;
  virtual eval::Trajectory KeyFrameTrajectory() const = 0;
  virtual slam::MapSummary Summary() const = 0;
  // A viewer's copy of the tracker's state after the last Track() (slam::System::View), asked
  // for from the tracking thread only while a viewer watches. false: this tracker has none
  // (fakes), and the viewer shows the numbers and the image only.
  virtual bool View(slam::SystemView* view, const slam::ViewRequest& request) {
    (void)view;
    (void)request;
    return false;
  }
  // Whether a viewer watches (slam::System::Watch): the tracker may then keep, while tracking,
  // what only a viewer shows. Tracking thread, between Track calls.
  virtual void Watch(bool watched) { (void)watched; }
};

// "not_initialized", "ok", "lost" (slam::ToString lives in the SLAM core, which runner does not
// link).
const char* StateName(slam::TrackingState state);

}  // namespace moslam::runner
