// The libtorch back end of semantic::MaskProvider: a segmentation network of the weakly supervised
// pipeline (networks.h), described by a model card of `type: torch` (semantic/model_card.h), run
// by TorchSegmenter and refined exactly like the ONNX segmenter's scores (semantic/mask_refine.h):
// the network's softmax (at its output stride) is resized bilinearly to the working size,
// test-time suppression compares the network's own image-level class scores (the auxiliary
// classifier's sigmoid) with refine.suppress_below, then the CRF, upsampling and dilation.
//
// This header does not include libtorch, so that runner/ and the apps can dispatch cards without
// compiling it; semantic/ cannot depend on this module (it depends on semantic/), hence
// MakeAnyMaskProvider here.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "moslam/semantic/mask_provider.h"
#include "moslam/semantic/model_card.h"

namespace moslam::net {

struct NetConfig;
class TorchSegmenter;

// Completes a torch card from its model's NetConfig: absent classes, movable, background and input
// size are taken from the model; given ones must agree (classes in the same order, the same
// background; mean/scale/rgb those of ImageToTensor: [127.5]*3, 1/127.5, rgb), except `movable`,
// which replaces the model's movable classes (each must be a class), and the input size, at which
// the provider runs the (fully convolutional) network instead of the size it was trained at
// (at least 32x32). InputError naming the card and key otherwise, or when the model is not a
// segmenter.
void CompleteTorchCard(const NetConfig& config, semantic::ModelCard* card);
// The same with the config read from card->model (InputError when it is not a model file).
void CompleteTorchCard(semantic::ModelCard* card);

// A completed torch card for a bare model file (name: the file's stem, default refinement).
semantic::ModelCard TorchModelCard(const std::string& model_path);

// semantic::LoadModelCard, and for a torch card CompleteTorchCard from its model file's config, so
// that SetMovable and the class names work before the network is loaded.
semantic::ModelCard LoadAnyModelCard(const std::string& path,
                                     const std::string& shared_root = semantic::SharedRoot());

class TorchMaskProvider : public semantic::MaskProvider {
 public:
  // card: a torch card (completed here if it is not yet); num_threads: libtorch's intra-op
  // threads for this process (at::set_num_threads). InputError naming the card or model file.
  TorchMaskProvider(const semantic::ModelCard& card, const semantic::RefineOptions& refine,
                    int num_threads = 2);
  ~TorchMaskProvider() override;

  // MaskResult::image_scores are the network's image-level class scores (what suppression read).
  semantic::Prediction Predict(const semantic::MaskInput& input) override;
  semantic::MaskResult Refine(semantic::Prediction prediction,
                              const semantic::MaskInput& input) override;
  const std::vector<std::string>& class_names() const override { return card_.classes; }
  const std::vector<bool>& movable() const override { return movable_; }
  std::string Describe() const override;
  const semantic::ModelCard& card() const { return card_; }

 private:
  std::unique_ptr<TorchSegmenter> segmenter_;  // first: the card is completed from its config
  semantic::ModelCard card_;
  std::vector<bool> movable_;
  semantic::MaskRefiner refiner_;
};

// Torch cards -> TorchMaskProvider; segmentation and detector cards -> semantic::MakeMaskProvider.
std::unique_ptr<semantic::MaskProvider> MakeAnyMaskProvider(const semantic::ModelCard& card,
                                                            const semantic::RefineOptions& refine);

}  // namespace moslam::net
