// Bounds on what lsgd reads from outside: every size taken from a file is
// checked against these before memory is committed, so a hostile or damaged
// input ends in an error naming the file and the value, never in an
// allocation the size of a number it holds.
#pragma once

#include <cstdint>

namespace lsgd {

// Frames of one sequence, ground truth, detections file or database: 10
// million (four days at 30 frames per second; KITTI-00 has 4,541).
constexpr std::int64_t kMaxFrames = 10'000'000;
// Pairs of one ground truth: 4,194,304 (about 40 MB held; the published
// ground truths have up to a few hundred thousand). A denser one (poses of
// a robot standing still, a MAT matrix of ones) is refused while it is
// read, not after gigabytes and seconds.
constexpr std::int64_t kMaxGroundTruthPairs = std::int64_t{1} << 22;
// Frame ids and database session ids: 2^53 - 1, so that every id is exact
// in JSON numbers (doubles) and in Python and JavaScript readers of them.
constexpr std::int64_t kMaxFrameId = (std::int64_t{1} << 53) - 1;
constexpr std::int64_t kMaxSession = kMaxFrameId;
// An image file: 1 GiB (a 16384 x 16384 BGRA image uncompressed).
constexpr std::int64_t kMaxImageFileBytes = std::int64_t{1} << 30;
// Pixels an image file may declare (sides at most kMaxImageSide, lsgd/image.h):
// 50 MP, 8192 x 6144 (201 MB as BGRA). io::read_image refuses more from the
// header, before anything is decoded.
constexpr std::int64_t kMaxImagePixels = std::int64_t{8192} * 6144;
// Memory a JPEG decoder may need besides the image (a progressive JPEG keeps
// every coefficient): io::read_image refuses more from the header.
constexpr std::int64_t kMaxJpegCoefficientBytes = std::int64_t{256} << 20;
// Scans of a progressive JPEG: each is a pass over every coefficient (a
// 99 KB file repeating one scan 1000 times took 14 s). Encoders write 10
// (libjpeg's progression) to a few dozen; io::read_image refuses more.
constexpr int kMaxJpegScans = 100;
// A score in a detections file (another system's similarity, distance or
// log-likelihood): at most 10^15 either side of 0. Scores of +-1e308 are
// finite, but their span is not (the report's charts were '-nan').
constexpr double kMaxDetectionScore = 1e15;
// A temporal window, tolerance or frame step: 10^9 frames.
constexpr std::int64_t kMaxWindowFrames = 1'000'000'000;
// A YAML configuration file: 64 KiB (a detector config with every option and
// its comment is about 4 KiB; yaml-cpp holds a node in some 500 bytes, so a
// MiB of empty items cost 550 MB before the first key was read).
constexpr std::int64_t kMaxConfigBytes = std::int64_t{1} << 16;
// One line of a text input (list file, ground truth, detections, poses,
// times): 64 KiB (a path is at most 4,096 bytes on Linux).
constexpr std::int64_t kMaxLineBytes = std::int64_t{1} << 16;

}  // namespace lsgd
