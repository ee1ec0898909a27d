// Constants of the segmorph animation stream, shared by encoder and decoder. Values are part of the format:
// never renumber them. The layout is specified in spec/ (bitstream appendix).
#pragma once

#include <cstddef>
#include <cstdint>

namespace segmorph::format {

constexpr uint8_t kMagic[4] = {'S', 'G', 'M', 'A'};
// Version 2 adds the flag kFlagTableResiduals (and the bytes after the body that it brings); a stream without it
// is laid out the same in both versions, and the encoder writes it as version 1, which more decoders read.
// Version 3 adds the flag kFlagFrameReferences, which it always has: each frame names the earlier frame of its clip
// that its motion and residuals are predicted from. The encoder writes version 3 only when a frame's reference is
// not the one versions 1 and 2 imply (the previous frame).
constexpr uint8_t kVersion = 1;
constexpr uint8_t kTableVersion = 2;
constexpr uint8_t kReferenceVersion = 3;
constexpr uint8_t kNewestVersion = kReferenceVersion;
constexpr size_t kHeaderBytes = 10;  // magic, version, flags, body length (u32, little endian); the body follows

// Flags byte.
constexpr uint8_t kFlagLossless = 1 << 0;           // residuals code float bit patterns exactly
constexpr uint8_t kFlagTemporalResiduals = 1 << 1;  // residuals are predicted from the previous frame's
constexpr uint8_t kFlagSpatialResiduals = 1 << 2;   // residuals are predicted from already decoded neighbours
constexpr uint8_t kFlagTableResiduals = 1 << 3;     // version 2: residuals in the table code, after the body
constexpr uint8_t kFlagFrameReferences = 1 << 4;    // version 3: each frame's reference frame is in the head
constexpr uint8_t kKnownFlags = kFlagLossless | kFlagTemporalResiduals | kFlagSpatialResiduals;  // version 1
constexpr uint8_t kKnownTableVersionFlags = kKnownFlags | kFlagTableResiduals;                   // version 2
constexpr uint8_t kKnownReferenceVersionFlags = kKnownTableVersionFlags | kFlagFrameReferences;  // version 3

// Limits a decoder enforces before allocating (a stream claiming more is refused as bad data).
constexpr uint32_t kMaxClips = 4096;
constexpr int64_t kMaxLosslessResidual = (int64_t(1) << 32) - 1;  // |difference of two ordered_bits values|
constexpr uint64_t kMaxVertexFrames = uint64_t(1) << 28;          // W × F: 268 million positions, 3 GiB of floats
constexpr uint32_t kMaxClusters = 65535;
constexpr uint32_t kMaxExtraWeights = 3;  // clusters blended into a vertex besides its own
constexpr int kMaxWeightBits = 16;        // weights are multiples of 2^-bits
constexpr uint32_t kMaxReferenceDistance = 255;  // version 3: a frame's reference is at most this many frames back

}  // namespace segmorph::format
