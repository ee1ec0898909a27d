// The syntax of an animation stream's head (everything before the residual steps; spec/bitstream.md): its adaptive
// contexts and code_head, the one walk over it that the writer (encode/stream_writer.cpp, HeadWriter) and the reader
// (decode/stream_reader.cpp, HeadReader) share, so that they cannot disagree on an order or a model: the writer's
// coder codes the value it is given, the reader's overwrites it with the one it reads and checks it, and grows the
// content's arrays only as the data proves to be there.
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "common/range_coder.h"
#include "common/stream.h"
#include "common/stream_format.h"
#include "segmorph/status.h"

namespace segmorph {
namespace stream_code {

inline int bits_for(uint32_t count) {  // bits of a bit tree that can code 0 .. count − 1
  int bits = 0;
  while (bits < 32 && (uint64_t(1) << bits) < count) ++bits;
  return bits;
}

// The adaptive contexts of a stream, in one place so that writer and reader cannot disagree.
struct Models {
  UnsignedModel count;                 // header counts
  BitModel group_welded;               // a group of identical base positions is one welded vertex
  UnsignedModel group_member;          // else: earlier member each member equals, or "new"
  UnsignedModel reference;             // version 3: each frame's reference distance
  std::array<SignedModel, 12> motion;  // per coefficient slot, deltas from the reference (or previous) frame
  // Version 3 with kFlagMotionContexts, instead: per slot and context (code_motion), what the prediction misses.
  std::array<std::array<SignedModel, 4>, 12> motion_contexts;
  BitTreeModel extra_count{2};         // extra clusters per vertex (0..3)
  SignedModel weight;
  // Version 3 with kFlagWeightContexts, instead (code_weights): the extra count in a context per count of the
  // previous welded vertex, and each extra cluster as its place among its own cluster's recent extras.
  std::array<BitTreeModel, 4> extra_count_contexts{BitTreeModel(2), BitTreeModel(2), BitTreeModel(2), BitTreeModel(2)};
  BitTreeModel recent_place{3};  // 0 .. kRecentWeightClusters − 1, or kRecentWeightClusters: the index follows
  // Version 4: the transform section (code_transform).
  BitTreeModel basis_source{2};
  SignedModel basis_entry;  // differences along time
  std::array<SignedModel, format::kCoefficientModels> coefficient;
  // The residuals' models are common/residual_contexts.h's.
};


inline Status corrupt(const std::string& what) { return Status(StatusCode::bad_data, "animation stream: " + what); }

// The header counts: the vertex count (which must be the base mesh's), the clips and their frames.
template <class Coder>
Status code_counts(Coder& coder, Models& models, const std::vector<float>& base, StreamContent& content) {
  coder.count(models.count, content.vertex_count);
  if (coder.failed()) return coder.status();
  if (content.vertex_count != base.size() / 3)
    return corrupt("it is for " + std::to_string(content.vertex_count) + " vertices, the base mesh has " +
                   std::to_string(base.size() / 3));
  uint32_t clips = uint32_t(content.clip_frames.size());
  coder.count(models.count, clips);
  if (coder.failed() || clips == 0 || clips > format::kMaxClips) return corrupt("bad clip count");
  uint64_t total_frames = 0;
  for (uint32_t c = 0; c < clips; ++c) {
    coder.grow(content.clip_frames, c + 1);
    coder.count(models.count, content.clip_frames[c]);
    total_frames += content.clip_frames[c];
    if (coder.failed() || content.clip_frames[c] == 0 || total_frames * content.vertex_count > format::kMaxVertexFrames)
      return corrupt("bad frame count");
  }
  return Status::Ok();
}

// Version 3: the reference window, then each frame's reference distance, clip by clip.
template <class Coder>
Status code_references(Coder& coder, Models& models, StreamContent& content) {
  if (!(content.flags & format::kFlagFrameReferences)) return Status::Ok();
  coder.count(models.count, content.reference_window);
  if (coder.failed() || content.reference_window == 0 || content.reference_window > format::kMaxReferenceDistance ||
      (content.reference_window > 1 &&
       uint64_t(content.reference_window) * content.vertex_count > format::kMaxReferenceWindowVertices))
    return corrupt("bad reference window");
  size_t frame = 0;
  for (uint32_t frames : content.clip_frames)
    for (uint32_t f = 0; f < frames; ++f, ++frame) {
      coder.grow(content.references, frame + 1);
      coder.count(models.reference, content.references[frame]);
      if (content.references[frame] > f || content.references[frame] > content.reference_window)
        return corrupt("a frame's reference is out of range");
      // Every frame: past the end of the data the decoder reads zeros, which are valid references, and the
      // references would grow with the frames the counts claim rather than with the data.
      if (coder.failed()) return coder.status();
    }
  return Status::Ok();
}

// Welding, group by group (groups of identical base positions, which the decoder finds itself): one bit "the group is
// one welded vertex"; otherwise, for each member after the first, the position within the group of the earlier member
// it welds to, or its own position when it starts a new welded vertex. Then the welded index of every vertex.
template <class Coder>
Status code_welding(Coder& coder, Models& models, const std::vector<float>& base, StreamContent& content) {
  std::vector<uint32_t> leader(content.vertex_count);
  std::iota(leader.begin(), leader.end(), 0u);
  for (const std::vector<uint32_t>& group : identical_position_groups(base)) {
    if (group.size() < 2) continue;
    uint32_t one = 1;
    if (!Coder::kReading)
      for (uint32_t v : group) one = one && content.welded_index[v] == content.welded_index[group[0]];
    coder.bit(models.group_welded, one);
    if (one) {
      for (uint32_t v : group) leader[v] = group[0];
      continue;
    }
    for (size_t j = 1; j < group.size(); ++j) {
      uint32_t target = uint32_t(j);
      if (!Coder::kReading)
        for (size_t i = 0; i < j && target == j; ++i)
          if (content.welded_index[group[i]] == content.welded_index[group[j]]) target = uint32_t(i);
      coder.count(models.group_member, target);
      if (target > j) return corrupt("bad welding");
      leader[group[j]] = target == j ? group[j] : leader[group[target]];
    }
    if (coder.failed()) return coder.status();
  }
  if (Coder::kReading) {
    content.welded_index.assign(content.vertex_count, UINT32_MAX);
    content.welded_count = 0;
    for (uint32_t v = 0; v < content.vertex_count; ++v)
      content.welded_index[v] = leader[v] == v ? content.welded_count++ : content.welded_index[leader[v]];
  }
  return Status::Ok();
}

// The clusters: their count, each welded vertex's label.
template <class Coder>
Status code_labels(Coder& coder, Models& models, StreamContent& content) {
  coder.count(models.count, content.cluster_count);
  if (coder.failed() || content.cluster_count == 0 || content.cluster_count > format::kMaxClusters ||
      content.cluster_count > content.welded_count)
    return corrupt("bad cluster count");
  BitTreeModel label_model(bits_for(content.cluster_count));
  coder.grow(content.labels, content.welded_count);
  for (size_t w = 0; w < content.welded_count; ++w) {
    coder.tree(label_model, content.labels[w]);
    if (content.labels[w] >= content.cluster_count) return corrupt("cluster label out of range");
  }
  return Status::Ok();
}

// The motion: its two steps, then per frame and cluster 12 coefficients, each as its difference from a prediction:
// the same coefficient in the frame's reference (version 3, a reference distance d > 0: the frame d back) or else
// in the previous frame of the stream (across clips; 0 for the first frame). Version 3 may add (spec/bitstream.md,
// 5.5): with kFlagMotionContexts, each slot's differences in one of four contexts, by the magnitude of the
// coefficient's last change (between the two frames before; 0, 1, 2 and more) for a frame whose base is the previous
// frame, 3 for a frame predicted from a reference further back; with kFlagLinearMotion too, a frame whose base is
// the previous frame, two or more frames into the stream, predicted as that frame's coefficient plus its last change
// (clamped to ±2^30). The motion grows a frame at a time as it is read, never sized up front by the counts: a stream
// of a few bytes can claim kMaxVertexFrames positions (gigabytes), and its data runs out long before memory would.
template <class Coder>
Status code_motion(Coder& coder, Models& models, StreamContent& content) {
  coder.float_bits(content.linear_step);
  coder.float_bits(content.translation_step);
  if (!(content.linear_step > 0) || !(content.translation_step > 0) || !std::isfinite(content.linear_step) ||
      !std::isfinite(content.translation_step))
    return corrupt("bad motion quantizer steps");
  const size_t clusters = content.cluster_count, frames = content.frame_count();
  if (uint64_t(frames) * clusters > format::kMaxVertexFrames) return corrupt("too many clusters for its frames");
  const bool references = content.flags & format::kFlagFrameReferences;
  const bool contexts = content.flags & format::kFlagMotionContexts;
  const bool linear = contexts && (content.flags & format::kFlagLinearMotion);
  const size_t row = clusters * 12;
  for (size_t f = 0; f < frames; ++f) {
    coder.grow(content.motion, (f + 1) * row);
    const size_t back = references && content.references[f] > 0 ? content.references[f] : 1;
    const bool changed = contexts && f >= 2 && back == 1;  // the last change is known
    for (size_t k = 0; k < clusters; ++k)
      for (size_t c = 0; c < 12; ++c) {
        const size_t index = (f * clusters + k) * 12 + c;
        int64_t prediction = f == 0 ? 0 : content.motion[index - back * row];
        size_t context = back > 1 ? 3 : 0;
        if (changed) {
          const int64_t change = prediction - content.motion[index - 2 * row];
          context = size_t(std::min<int64_t>(change < 0 ? -change : change, 2));
          if (linear) prediction = std::clamp<int64_t>(prediction + change, -(int64_t(1) << 30), int64_t(1) << 30);
        }
        // The writer's difference (its coefficients are within ±2^29: it fits); the reader's is overwritten.
        int32_t delta = int32_t(int64_t(content.motion[index]) - prediction);
        coder.integer(contexts ? models.motion_contexts[c][context] : models.motion[c], delta);
        const int64_t value = prediction + delta;
        if (value < INT32_MIN || value > INT32_MAX) return corrupt("motion coefficient out of range");
        if (Coder::kReading) content.motion[index] = int32_t(value);
      }
    if (coder.failed()) return coder.status();
  }
  return Status::Ok();
}

// The weights: their precision, then per welded vertex its extra clusters and their weights. Version 3 with
// kFlagWeightContexts (spec/bitstream.md, 5.6): the count of extras in the context of the previous welded vertex's
// count, and each extra cluster as its place in a list of the kRecentWeightClusters clusters most recently blended
// into vertices of the same own cluster (most recent first; the place past the end escapes to the cluster's index),
// which then moves to the front of that list.
template <class Coder>
Status code_weights(Coder& coder, Models& models, StreamContent& content) {
  uint32_t weight_bits = uint32_t(content.weight_bits);
  coder.count(models.count, weight_bits);
  if (Coder::kReading) content.weight_bits = int(weight_bits);
  if (content.weight_bits < 1 || content.weight_bits > format::kMaxWeightBits) return corrupt("bad weight precision");
  BitTreeModel cluster_model(bits_for(content.cluster_count));
  const bool contexts = content.flags & format::kFlagWeightContexts;
  constexpr uint32_t kRecent = format::kRecentWeightClusters, kEmpty = UINT32_MAX;
  std::vector<uint32_t> recent;  // per own cluster kRecent places, most recent first
  if (contexts) recent.assign(size_t(content.cluster_count) * kRecent, kEmpty);
  uint32_t previous_extra = 0;
  if (Coder::kReading) content.weight_offset.assign(1, 0);
  for (size_t w = 0; w < content.welded_count; ++w) {
    const uint32_t first = content.weight_offset[w];
    uint32_t extra = Coder::kReading ? 0 : content.weight_offset[w + 1] - first;
    coder.tree(contexts ? models.extra_count_contexts[previous_extra] : models.extra_count, extra);
    if (extra > format::kMaxExtraWeights) return corrupt("too many weights");
    previous_extra = extra;
    coder.grow(content.weight_cluster, first + extra);
    coder.grow(content.weight_value, first + extra);
    uint32_t* list = contexts ? &recent[size_t(content.labels[w]) * kRecent] : nullptr;
    for (uint32_t i = first; i < first + extra; ++i) {
      uint32_t place = kRecent;
      if (contexts) {
        if (!Coder::kReading) place = uint32_t(std::find(list, list + kRecent, content.weight_cluster[i]) - list);
        coder.tree(models.recent_place, place);
      }
      if (place == kRecent)
        coder.tree(cluster_model, content.weight_cluster[i]);
      else if (Coder::kReading)
        content.weight_cluster[i] = list[place];
      if (content.weight_cluster[i] >= content.cluster_count) return corrupt("weight cluster out of range");
      if (contexts) {  // to the front; an escape drops the last place
        const uint32_t moved = std::min(place, kRecent - 1);
        std::copy_backward(list, list + moved, list + moved + 1);
        list[0] = content.weight_cluster[i];
      }
      coder.integer(models.weight, content.weight_value[i]);
    }
    if (Coder::kReading) content.weight_offset.push_back(first + extra);
    if (coder.failed()) return coder.status();
  }
  return Status::Ok();
}

// Everything before the residual symbols, the residual steps included.
template <class Coder>
Status code_head(Coder& coder, Models& models, const std::vector<float>& base, StreamContent& content) {
  SEGMORPH_RETURN_IF_ERROR(code_counts(coder, models, base, content));
  SEGMORPH_RETURN_IF_ERROR(code_references(coder, models, content));
  SEGMORPH_RETURN_IF_ERROR(code_welding(coder, models, base, content));
  SEGMORPH_RETURN_IF_ERROR(code_labels(coder, models, content));
  SEGMORPH_RETURN_IF_ERROR(code_motion(coder, models, content));
  SEGMORPH_RETURN_IF_ERROR(code_weights(coder, models, content));
  return Status::Ok();
}

// Version 4: `vectors` basis vectors of `frames` entries each, appended to `basis`: per vector its step, then its
// entries as differences along time (from 0 before the first). `entries` counts the entries of all bases so far.
template <class Coder>
Status code_basis(Coder& coder, Models& models, size_t frames, size_t vectors, StreamContent::Basis& basis,
                  uint64_t& entries) {
  for (size_t i = 0; i < vectors; ++i) {
    entries += frames;
    if (entries > format::kMaxBasisEntries) return corrupt("too many basis entries");
    coder.grow(basis.step, i + 1);
    coder.float_bits(basis.step[i]);
    if (!(basis.step[i] > 0) || !std::isfinite(basis.step[i])) return corrupt("bad basis step");
    coder.grow(basis.entries, (i + 1) * frames);
    int64_t previous = 0;
    for (size_t f = 0; f < frames; ++f) {
      int32_t& entry = basis.entries[i * frames + f];
      // The writer's entries lie within ±kMaxTransformValue: the difference fits; the reader's is overwritten.
      int32_t difference = int32_t(int64_t(entry) - previous);
      coder.integer(models.basis_entry, difference);
      previous += difference;
      if (previous < -format::kMaxTransformValue || previous > format::kMaxTransformValue)
        return corrupt("basis entry out of range");
      if (Coder::kReading) entry = int32_t(previous);
    }
    if (coder.failed()) return coder.status();
  }
  return Status::Ok();
}

// Version 4's transform section (spec/bitstream.md, 5.9): the stream's basis; per cluster its basis's source, size,
// coefficient step and (its own) vectors; then the coefficients' symbols, cluster by cluster, vector by vector, axis
// by axis, the cluster's welded vertices ascending, in a model per vector (the first kCoefficientModels − 1, then
// one for the rest). The symbols grow a block at a time as the data proves to be there.
template <class Coder>
Status code_transform(Coder& coder, Models& models, StreamContent& content) {
  const size_t frames = content.frame_count(), clusters = content.cluster_count;
  uint32_t stream_vectors = uint32_t(content.stream_basis.size());
  coder.count(models.count, stream_vectors);
  if (coder.failed()) return coder.status();
  if (stream_vectors > frames) return corrupt("bad basis size");
  uint64_t entries = 0;
  SEGMORPH_RETURN_IF_ERROR(code_basis(coder, models, frames, stream_vectors, content.stream_basis, entries));
  std::vector<std::vector<uint32_t>> members(clusters);
  for (uint32_t w = 0; w < content.welded_count; ++w) members[content.labels[w]].push_back(w);
  uint64_t coefficients = 0;
  for (size_t k = 0; k < clusters; ++k) {
    coder.grow(content.basis_source, k + 1);
    coder.grow(content.basis_size, k + 1);
    coder.grow(content.coefficient_step, k + 1);
    coder.grow(content.own_basis, k + 1);
    coder.tree(models.basis_source, content.basis_source[k]);
    if (coder.failed()) return coder.status();
    const uint32_t source = content.basis_source[k];
    if (source > format::kBasisOwn) return corrupt("bad basis source");
    if (source == format::kBasisNone) continue;
    coder.count(models.count, content.basis_size[k]);
    const uint32_t size = content.basis_size[k];
    if (coder.failed() || size == 0 || size > format::kMaxBasisSize ||
        size > (source == format::kBasisStream ? stream_vectors : frames))
      return corrupt("bad basis size");
    coder.float_bits(content.coefficient_step[k]);
    if (!(content.coefficient_step[k] > 0) || !std::isfinite(content.coefficient_step[k]))
      return corrupt("bad coefficient step");
    if (source == format::kBasisOwn)
      SEGMORPH_RETURN_IF_ERROR(code_basis(coder, models, frames, size, content.own_basis[k], entries));
    coefficients += uint64_t(size) * 3 * members[k].size();
    if (coefficients > format::kMaxTransformCoefficients) return corrupt("too many coefficients");
  }
  size_t at = 0;
  for (size_t k = 0; k < clusters; ++k)
    for (uint32_t i = 0; i < content.basis_size[k]; ++i) {
      SignedModel& model = models.coefficient[std::min<size_t>(i, format::kCoefficientModels - 1)];
      for (int axis = 0; axis < 3; ++axis) {
        coder.grow(content.coefficient_symbols, at + members[k].size());
        coder.integers(model, &content.coefficient_symbols[at], members[k].size());
        at += members[k].size();
        if (coder.failed()) return coder.status();
      }
    }
  return Status::Ok();
}

// The residual quantizer steps, one per axis (lossless streams: not used). The encoder writes streams without
// residuals only to measure everything else (their steps are not chosen yet): the writer checks the steps of a stream
// that has residuals, the reader those of every stream.
template <class Coder>
Status code_residual_steps(Coder& coder, StreamContent& content) {
  const bool checked = !(content.flags & format::kFlagLossless) &&
                       (Coder::kReading || !content.residuals.empty() || !content.narrow_residuals.empty());
  for (int axis = 0; axis < 3; ++axis) {
    coder.float_bits(content.residual_step[axis]);
    if (checked && (!(content.residual_step[axis] > 0) || !std::isfinite(content.residual_step[axis])))
      return corrupt("bad residual quantizer step");
  }
  return coder.failed() ? coder.status() : Status::Ok();
}

}  // namespace stream_code
}  // namespace segmorph
