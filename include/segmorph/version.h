/* segmorph's version, written here and nowhere else (CMakeLists.txt reads it), and the versions of the streams its
 * decoder reads. C and C++. */
#ifndef SEGMORPH_VERSION_H
#define SEGMORPH_VERSION_H

#define SEGMORPH_VERSION_MAJOR 0
#define SEGMORPH_VERSION_MINOR 1
#define SEGMORPH_VERSION_PATCH 0

/* major * 1000 + minor * 10 + patch, as meshoptimizer counts: 0.1.0 is 10. */
#define SEGMORPH_VERSION (SEGMORPH_VERSION_MAJOR * 1000 + SEGMORPH_VERSION_MINOR * 10 + SEGMORPH_VERSION_PATCH)

/* The animation streams this decoder reads (spec/bitstream.md: versions 1 to 4) and the track stream
 * (spec/tracks.md: version 1). */
#define SEGMORPH_STREAM_VERSION_MIN 1
#define SEGMORPH_STREAM_VERSION_MAX 4
#define SEGMORPH_TRACK_STREAM_VERSION 1

/* Marks the library's API. The shared library exports these symbols and nothing else. */
#if defined(_WIN32) && defined(SEGMORPH_SHARED)
#ifdef SEGMORPH_BUILDING_LIBRARY
#define SEGMORPH_API __declspec(dllexport)
#else
#define SEGMORPH_API __declspec(dllimport)
#endif
#elif defined(__GNUC__) || defined(__clang__)
#define SEGMORPH_API __attribute__((visibility("default")))
#else
#define SEGMORPH_API
#endif

#endif
