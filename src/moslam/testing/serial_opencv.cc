// Linked into every test binary of the ThreadSanitizer build (moslam_test in
// cmake/MoslamHelpers.cmake), as a source of the executable so that the linker keeps it.
//
// OpenCV's parallel loops (cv::parallel_for_, behind resize, dilate, cvtColor, ...) run on TBB's
// worker threads. libtbb is not built with ThreadSanitizer, so its hand-overs are invisible to it:
// a buffer a TBB worker allocates inside OpenCV and the calling thread frees reads as a race
// (measured: cv::dilate's buffers in slam::FrameMask, 3 reports per run of slam/system_threads).
// OPENCV_FOR_THREADS_NUM does not reach the TBB backend of Debian's OpenCV 4.6; setNumThreads(0)
// does: OpenCV then runs every loop in the calling thread, and the threads this build checks are
// the ones moslam starts.
#include <opencv2/core/utility.hpp>

namespace {

const bool kOpenCvSerial = [] {
  cv::setNumThreads(0);
  return true;
}();

}  // namespace
