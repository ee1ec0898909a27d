// The PC2 and MDD readers against hand-made files: every header field, both byte orders, and bad files refused
// before any allocation their header would ask for.
#include "caches/point_cache.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "cache_files.h"
#include "test_files.h"

namespace segmorph {
namespace {

using testing::coordinate;
using testing::mdd;
using testing::pc2;
using testing::put;
using testing::put_float;
using testing::temporary_path;
using testing::written;

void expect_frames(PointCacheReader& reader, size_t frames, size_t points) {
  ASSERT_EQ(reader.frame_count(), frames);
  ASSERT_EQ(reader.point_count(), points);
  std::vector<float> positions;
  for (size_t f = frames; f-- > 0;) {  // any order
    ASSERT_TRUE(reader.read_frame(f, positions).ok());
    ASSERT_EQ(positions.size(), points * 3);
    for (size_t p = 0; p < points; ++p)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(positions[p * 3 + size_t(c)], coordinate(f, p, c)) << f << " " << p;
  }
  EXPECT_FALSE(reader.read_frame(frames, positions).ok());
}

TEST(PointCache, Pc2FieldsFramesAndTimes) {
  PointCacheReader reader;
  ASSERT_TRUE(reader.open(written("a.pc2", pc2(5, 4, 10, 2))).ok());
  EXPECT_EQ(reader.format(), PointCacheReader::Format::pc2);
  expect_frames(reader, 4, 5);
  EXPECT_EQ(reader.times(30), (std::vector<float>{10.f / 30, 12.f / 30, 14.f / 30, 16.f / 30}));
}

TEST(PointCache, MddFieldsFramesAndTimesAreBigEndian) {
  PointCacheReader reader;
  ASSERT_TRUE(reader.open(written("a.mdd", mdd(3, 7, {0, 0.04f, 0.08f}))).ok());
  EXPECT_EQ(reader.format(), PointCacheReader::Format::mdd);
  expect_frames(reader, 3, 7);
  EXPECT_EQ(reader.times(30), (std::vector<float>{0, 0.04f, 0.08f}));  // its own times, whatever the rate
}

TEST(PointCache, BadFilesAreRefusedWithTheReason) {
  const auto refused = [](const std::string& name, const std::string& bytes, const std::string& reason) {
    PointCacheReader reader;
    const Status status = reader.open(written(name, bytes));
    EXPECT_EQ(status.code(), StatusCode::bad_data) << name;
    EXPECT_NE(status.message().find(reason), std::string::npos) << name << ": " << status.message();
  };
  std::string good = pc2(5, 4, 0, 1);
  refused("truncated.pc2", good.substr(0, good.size() - 1), "(truncated)");
  refused("longer.pc2", good + "x", "the file 273");
  refused("version.pc2", pc2(5, 4, 0, 1, 2), "PC2 version 2");
  refused("rate.pc2", pc2(5, 4, 0, 0), "sample rate");
  // Absurd counts in a small file: refused before anything is allocated (ASan would report a huge allocation).
  std::string absurd = good;
  absurd[16] = absurd[17] = absurd[18] = char(0xff), absurd[19] = 0x0f;  // 2^28 - 1 points
  refused("absurd.pc2", absurd, "is 12884901872 bytes, the file 272 (truncated)");
  absurd[19] = char(0x7f);
  refused("absurder.pc2", absurd, "PC2 header claims");
  refused("empty.pc2", "", "neither a PC2 nor an MDD");
  std::string header;
  put(header, 0x00ffffff, true);
  put(header, 0x0fffffff, true);
  refused("absurd.mdd", header, "bytes, the file 8 (truncated)");
  refused("zero.mdd", mdd(0, 3, {}), "claims 0 frames");
  refused("times.mdd", mdd(3, 2, {0, 0.1f, 0.1f}), "frame 2's time");
  std::string not_finite = mdd(2, 2, {0, 1});
  PointCacheReader reader;
  const size_t at = 8 + 8 + 12 + 4;  // frame 0, point 1, y
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::string bits;
  put_float(bits, nan, true);
  not_finite.replace(at, 4, bits);
  ASSERT_TRUE(reader.open(written("nan.mdd", not_finite)).ok());
  std::vector<float> positions;
  const Status status = reader.read_frame(0, positions);
  EXPECT_EQ(status.code(), StatusCode::bad_data);
  EXPECT_EQ(status.message(), "frame 0, point 1: not a finite position");
  EXPECT_TRUE(reader.read_frame(1, positions).ok());
  EXPECT_EQ(PointCacheReader().open(temporary_path("missing.pc2")).code(), StatusCode::io_error);
}

}  // namespace
}  // namespace segmorph
