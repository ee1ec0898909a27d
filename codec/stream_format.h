// Constants of the segmorph animation stream, shared by encoder and decoder. Values are part of the format:
// never renumber them. The layout is specified in spec/ (bitstream appendix).
#pragma once

#include <cstddef>
#include <cstdint>

namespace segmorph::format {

constexpr uint8_t kMagic[4] = {'S', 'G', 'M', 'A'};
// Version 2 adds the flag kFlagTableResiduals (and the bytes after the body that it brings); a stream without it
// is laid out the same in both versions, and the encoder writes it as version 1, which more decoders read.
// Version 3 adds the flags kFlagFrameReferences (each frame names the earlier frame of its clip that its motion and
// residuals are predicted from), kFlagMotionContexts (the motion's differences coded in contexts of its last change)
// and kFlagLinearMotion (the motion predicted from the two frames before), and kFlagWeightContexts (each vertex's
// extra clusters coded as places among the clusters recently blended into its own cluster's vertices). The encoder
// writes version 3 only when it sets one of them, which it does where they pay.
constexpr uint8_t kVersion = 1;
constexpr uint8_t kTableVersion = 2;
constexpr uint8_t kReferenceVersion = 3;  // frame references and linear motion
constexpr uint8_t kNewestVersion = kReferenceVersion;
constexpr size_t kHeaderBytes = 10;  // magic, version, flags, body length (u32, little endian); the body follows

// Flags byte.
constexpr uint8_t kFlagLossless = 1 << 0;           // residuals code float bit patterns exactly
constexpr uint8_t kFlagTemporalResiduals = 1 << 1;  // residuals are predicted from the reference frame's
constexpr uint8_t kFlagSpatialResiduals = 1 << 2;   // residuals are predicted from already decoded neighbours
constexpr uint8_t kFlagTableResiduals = 1 << 3;     // version 2: residuals in the table code, after the body
constexpr uint8_t kFlagFrameReferences = 1 << 4;    // version 3: each frame's reference frame is in the head
constexpr uint8_t kFlagMotionContexts = 1 << 5;     // version 3: motion differences coded in contexts
constexpr uint8_t kFlagLinearMotion = 1 << 6;       // version 3, with kFlagMotionContexts: and predicted linearly
constexpr uint8_t kFlagWeightContexts = 1 << 7;     // version 3: weights coded in contexts of recent ones
constexpr uint8_t kKnownFlags = kFlagLossless | kFlagTemporalResiduals | kFlagSpatialResiduals;  // version 1
constexpr uint8_t kKnownTableVersionFlags = kKnownFlags | kFlagTableResiduals;                   // version 2
constexpr uint8_t kKnownReferenceVersionFlags = kKnownTableVersionFlags | kFlagFrameReferences | kFlagMotionContexts |
                                                kFlagLinearMotion | kFlagWeightContexts;  // version 3

// Limits a decoder enforces before allocating (a stream claiming more is refused as bad data).
constexpr uint32_t kMaxClips = 4096;
constexpr int64_t kMaxLosslessResidual = (int64_t(1) << 32) - 1;  // |difference of two ordered_bits values|
constexpr uint64_t kMaxVertexFrames = uint64_t(1) << 28;          // W × F: 268 million positions, 3 GiB of floats
constexpr uint32_t kMaxClusters = 65535;
constexpr uint32_t kMaxExtraWeights = 3;  // clusters blended into a vertex besides its own
constexpr int kMaxWeightBits = 16;        // weights are multiples of 2^-bits
// Version 3 with kFlagWeightContexts: each cluster's recent extra clusters, a place among which codes an extra
// cluster; place kRecentWeightClusters is an escape to the cluster's index.
constexpr uint32_t kRecentWeightClusters = 7;
constexpr uint32_t kMaxReferenceDistance = 255;  // version 3: a frame's reference is at most this many frames back
// Version 3: a reference window above 1 times V is at most this, so that the residuals a decoder holds for the
// window ((window + 2) × W × 3 doubles) stay within about 48 MiB plus the 3 frames any decoder holds.
constexpr uint64_t kMaxReferenceWindowVertices = uint64_t(1) << 21;

}  // namespace segmorph::format
