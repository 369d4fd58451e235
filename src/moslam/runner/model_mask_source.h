// The network mask sources of `moslam run` (--mask-source onnx | detector | model): a
// semantic::MaskProvider, built from a model card (net::MakeAnyMaskProvider), behind
// runner::MaskSource.
#pragma once

#include <memory>

#include "moslam/runner/mask_source.h"
#include "moslam/semantic/mask_provider.h"

namespace moslam::runner {

// Loads options.model_card (its refine settings, with options.crf, options.dilate_px and
// options.movable overriding the card's when given) and the network. InputError when the card's
// type does not match the kind (an onnx source needs a segmentation card, a detector a detector
// card, model a torch card; model without a card takes kDefaultTorchCard), or naming the card or
// model file.
std::unique_ptr<MaskSource> MakeModelMaskSource(const MaskOptions& options);

// The same over a provider built elsewhere (tests use fakes).
std::unique_ptr<MaskSource> MakeProviderMaskSource(
    std::unique_ptr<semantic::MaskProvider> provider);

}  // namespace moslam::runner
