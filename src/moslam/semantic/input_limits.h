// Bounds on the sizes a model card or the command line may ask the mask providers for, refused
// when the options are checked (ModelCard::Check, RefineOptions::Check, runner::MaskOptions), so
// that an absurd value is an InputError naming its key, not a failure inside OpenCV dnn or a run
// that does not end.
#pragma once

namespace moslam::semantic {

// A card's input_width and input_height, pixels a side. Below the minimum the strided layers of a
// network leave nothing (OpenCV dnn fails inside a layer: 1x1, 7x5); above the maximum one frame
// takes seconds and gigabytes (an 8000x6000 input took over a minute a frame). The shipped cards
// use 320 to 513.
constexpr int kMinCardInputSide = 32;
constexpr int kMaxCardInputSide = 2048;
// Darknet detectors (a card with `config`) downsample by 32 and concatenate upsampled maps with
// earlier ones: any other input size makes the concatenated shapes disagree.
constexpr int kDarknetInputMultiple = 32;

// The largest mask dilation, pixels (refine.dilate_px, `moslam run --mask-dilate`,
// `moslam segment --mask-dilate`). OpenCV dilates with an elliptic element point by point, so the
// cost grows with the element's area: one 640x480 mask on the 2-core machine took 0.6 ms at 5 px,
// 29 ms at 50, 106 ms at 100 and 407 ms at 200 (2026-12-03), so 5000 px ran for minutes a frame.
// A mask grown by 100 px already covers a third of such a frame's width.
constexpr int kMaxDilatePx = 100;

}  // namespace moslam::semantic
