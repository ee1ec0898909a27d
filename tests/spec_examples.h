// The worked examples of spec/bitstream.md (section 9: version 1; 9.7: version 3; 9.8: version 4) as data: each
// stream's bytes, the base mesh it decodes against and the frames it decodes to. Shared by stream_example_test.cpp
// (which builds the streams from their content and checks these bytes) and decoder_only_test.cpp (which decodes the
// bytes with the runtime decoder's library alone). When the format changes, stream_example_test's failure messages
// print the new bytes and frames: paste them here and into the spec.
#pragma once

#include <cstdint>
#include <vector>

namespace segmorph {
namespace spec_examples {

// Section 9: two clips (2 frames and 1) over the base below.
inline constexpr char kExampleHex[] =
    "53474d4101063e000000100445d5db1a3c8ed7bc141eada18000000037ee2e161dd2d2d31f1aaf4c3e8b4fa4457ea8dd"
    "3449f56ffaa1356ffcb1f97f6a474ecd6c2ad438a41450d2";

// Base positions (V = 8): a strip of two unit squares, with vertex 6 a seam copy of vertex 4 (welded) and
// vertex 7 a copy of vertex 2 that moves on its own (not welded).
inline std::vector<float> example_base() {
  return {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0, 1, 1, 0, 2, 0, 0};
}


inline std::vector<uint32_t> example_triangles() {
  return {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 6, 2, 7, 5};
}


// The decoded frames (clip 0: frames 0 and 1; clip 1: frame 2), V × 3 binary32 bit patterns each.
inline constexpr uint32_t kExampleFrames[3][8][3] = {
    {{0x00000000, 0x00000000, 0x00000000},
     {0x3f800000, 0x00000000, 0x00000000},
     {0x40000000, 0x00000000, 0x00000000},
     {0x00000000, 0x3f7d70a4, 0x00000000},
     {0x3f800000, 0x3f7f258c, 0x00000000},
     {0x40000000, 0x3f7fb72f, 0x00000000},
     {0x3f800000, 0x3f7f258c, 0x00000000},
     {0x400147ae, 0xba11a2b4, 0x00000000}},
    {{0x3cd1eb85, 0x00000000, 0x00000000},
     {0x3f82c7ae, 0xbc23d70a, 0x3d800000},
     {0x40009bd7, 0xbc23d70a, 0x3ea2b852},
     {0x3cd1eb85, 0x3f7d70a4, 0x00000000},
     {0x3f807852, 0x3f7e4b18, 0x3d51eb85},
     {0x4000369d, 0x3f7db975, 0x3e8da741},
     {0x3f807852, 0x3f7e4b18, 0x3d51eb85},
     {0x4001b4e8, 0x3a11a2b4, 0x3e8bf259}},
    {{0xbc800000, 0x00000000, 0x00000000},
     {0x3f887259, 0x3c23d70a, 0x3d000000},
     {0x3fff37ae, 0x3c23d70a, 0x3e040000},
     {0xbc800000, 0x3f828f5c, 0x00000000},
     {0x3f89828f, 0x3f8147ae, 0x3c800000},
     {0x400130ed, 0x3f8147ae, 0x3e000000},
     {0x3f89828f, 0x3f8147ae, 0x3c800000},
     {0x3fff2a19, 0x3c23d70a, 0x3e666666}},
};

// The worked example of version 3 (spec/bitstream.md, section 9.7): the same mesh, clusters, weights and steps, one
// clip of 4 frames whose frames 2 and 3 name frames 0 and 1 as their references (window 2).
inline constexpr char kReferenceExampleHex[] =
    "53474d4103163e00000010023ae6a02f4034f06e3dd826442509eaa00000000b8529a2402d4604caa68424224eb9e57e"
    "9b20c6b3d9b825c1d8b836be2eb382b857f31cf5e487e30a";

// Its decoded frames: "frame vertex x y z", binary32 bit patterns.
inline constexpr char kReferenceExampleFrames[] =
    "0 0 00000000 00000000 00000000\n"
    "0 1 3f800000 00000000 00000000\n"
    "0 2 40000000 00000000 00000000\n"
    "0 3 00000000 3f7d70a4 00000000\n"
    "0 4 3f800000 3f7f258c 00000000\n"
    "0 5 40000000 3f7fb72f 00000000\n"
    "0 6 3f800000 3f7f258c 00000000\n"
    "0 7 400147ae ba11a2b4 00000000\n"
    "1 0 3cd1eb85 00000000 00000000\n"
    "1 1 3f82c7ae bc23d70a 3d800000\n"
    "1 2 40009bd7 bc23d70a 3ea2b852\n"
    "1 3 3cd1eb85 3f7d70a4 00000000\n"
    "1 4 3f807852 3f7e4b18 3d51eb85\n"
    "1 5 4000369d 3f7db975 3e8da741\n"
    "1 6 3f807852 3f7e4b18 3d51eb85\n"
    "1 7 4001b4e8 3a11a2b4 3e8bf259\n"
    "2 0 00000000 00000000 00000000\n"
    "2 1 3f800000 00000000 3b800000\n"
    "2 2 40000000 00000000 3c840000\n"
    "2 3 00000000 3f7d70a4 00000000\n"
    "2 4 3f800000 3f7f258c 3b000000\n"
    "2 5 40000000 3f7fb72f 3c800000\n"
    "2 6 3f800000 3f7f258c 3b000000\n"
    "2 7 400147ae ba11a2b4 3c800000\n"
    "3 0 3cd1eb85 00000000 00000000\n"
    "3 1 3f82c7ae bc23d70a 3d800000\n"
    "3 2 40009bd7 bc23d70a 3ea2b852\n"
    "3 3 3cd1eb85 3f7d70a4 00000000\n"
    "3 4 3f81c000 3f7e4b18 3d51eb85\n"
    "3 5 40006d3a 3f7db975 3e8da741\n"
    "3 6 3f81c000 3f7e4b18 3d51eb85\n"
    "3 7 4001d037 3a11a2b4 3e8bf259\n";

// The worked example of version 4 (spec/bitstream.md, section 9.8): the head of section 9's stream (clips, welding,
// clusters, motion, weights), then the residuals as bases and coefficients: cluster 0 takes the stream's one vector,
// cluster 1 two of its own.
inline constexpr char kTransformExampleHex[] =
    "53474d410400530000001004"
    "45d5db1a3c8ed7bc141eada18000000037ee2e161dd2d2d31f1aaf4c3e8b4fa4457ea8dc5c43eabfa71334d7f91f6421984c2dcc3d9802"
    "dc4948c53212f801af198b1c0f3d1a23669fcf86956f437332a6";

// Its decoded frames: "frame vertex x y z", binary32 bit patterns.
inline constexpr char kTransformExampleFrames[] =
    "0 0 00000000 00000000 00000000\n"
    "0 1 3f800000 00000000 00000000\n"
    "0 2 40000000 3b23d70a 00000000\n"
    "0 3 00000000 3f800000 00000000\n"
    "0 4 3f800000 3f800000 00000000\n"
    "0 5 40000000 3f8051ec 00000000\n"
    "0 6 3f800000 3f800000 00000000\n"
    "0 7 40000000 00000000 3ba3d70a\n"
    "1 0 3cd1eb85 00000000 00000000\n"
    "1 1 3f82c7ae 00000000 3d8a3d71\n"
    "1 2 400516b8 00000000 3e73851f\n"
    "1 3 3cfae148 3f800000 3ba3d70a\n"
    "1 4 3f811c29 3f80a3d7 3d147ae1\n"
    "1 5 40051eb8 3f800000 3e800000\n"
    "1 6 3f811c29 3f80a3d7 3d147ae1\n"
    "1 7 40066666 00000000 3e800000\n"
    "2 0 3b8f5c28 00000000 00000000\n"
    "2 1 3f89ba07 00000000 3d28f5c2\n"
    "2 2 3ff8d148 3b23d70a 3e0e3d71\n"
    "2 3 3c6b851e 3f800000 3c23d70a\n"
    "2 4 3f87cda7 3f8147ae 3cd1eb85\n"
    "2 5 3ffd8bf2 3f8051ec 3e000000\n"
    "2 6 3f87cda7 3f8147ae 3cd1eb85\n"
    "2 7 3ff84444 00000000 3e051eb8\n";

}  // namespace spec_examples
}  // namespace segmorph
