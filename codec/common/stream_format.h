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
// Version 4 codes the residuals as temporal bases and coefficients (the transform section) instead of residual
// symbols: the flags are version 3's, less the four of the residual loop (LOSSLESS, TEMPORAL, SPATIAL, TABLE), which
// must be clear; REFERENCES no longer needs TEMPORAL (the motion still uses the references). The encoder writes it
// where it measures a smaller stream than the residual loop's at no more error.
constexpr uint8_t kAdaptiveVersion = 1;  // the adaptive residual code, the first version
constexpr uint8_t kTableVersion = 2;
constexpr uint8_t kReferenceVersion = 3;  // frame references and linear motion
constexpr uint8_t kTransformVersion = 4;  // the residuals as temporal bases and coefficients
constexpr uint8_t kOldestVersion = kAdaptiveVersion;  // the versions a decoder reads: kOldestVersion to kNewestVersion
constexpr uint8_t kNewestVersion = kTransformVersion;
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
constexpr uint8_t kResidualLoopFlags =
    kFlagLossless | kFlagTemporalResiduals | kFlagSpatialResiduals | kFlagTableResiduals;  // clear in version 4
constexpr uint8_t kKnownTransformVersionFlags = kKnownReferenceVersionFlags & ~kResidualLoopFlags;  // version 4

// Version 4: where each cluster's basis comes from.
constexpr uint32_t kBasisNone = 0;           // the cluster's residuals are zero
constexpr uint32_t kBasisStream = 1;         // the first m vectors of the stream's basis
constexpr uint32_t kBasisOwn = 2;            // m vectors of its own
constexpr uint32_t kCoefficientModels = 16;  // the coefficients of vector i are coded in model min(i, 15)

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
// Version 4: every basis entry and every coefficient lies within ±kMaxTransformValue (so that the entries'
// differences fit 32 bits and every product and sum of the reconstruction is exact enough in binary64); the bases
// hold at most kMaxBasisEntries entries in all (vectors × F: 128 MiB of doubles), the clusters at most
// kMaxTransformCoefficients coefficients (512 MiB of int32).
constexpr int64_t kMaxTransformValue = int64_t(1) << 30;
// Version 4: a cluster uses at most this many basis vectors (the decoder's work per vertex-frame is 3 m products).
constexpr uint32_t kMaxBasisSize = 256;
// Version 4: W × F is at most this many times the body's length plus 4 (versions 1 to 3 code a decision per
// welded vertex-frame, which bounds it so; version 4 codes none, and keeps the bound as a rule so that the bytes
// still back the frames a decoder is asked to make).
constexpr uint64_t kMaxVertexFramesPerByte = 364;
constexpr uint64_t kMaxBasisEntries = uint64_t(1) << 24;
constexpr uint64_t kMaxTransformCoefficients = uint64_t(1) << 27;

}  // namespace segmorph::format
