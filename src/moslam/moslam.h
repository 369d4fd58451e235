// moslam as a library: the one header a program that embeds it includes (docs/RUNNING.md,
// "moslam inside other programs"; examples/ has a whole program). With the installed package:
//
//   find_package(moslam REQUIRED)
//   target_link_libraries(my_program PRIVATE moslam::api)
//
// or `pkg-config --cflags --libs moslam`.
#pragma once

#include "moslam/api/segmenter.h"       // IWYU pragma: export
#include "moslam/api/slam.h"            // IWYU pragma: export
#include "moslam/eval/trajectory_io.h"  // IWYU pragma: export
#include "moslam/util/error.h"          // IWYU pragma: export
