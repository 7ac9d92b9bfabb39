// Checked image loading. cv::imread alone returns an empty or partly decoded Mat for a truncated file, so
// the encoded bytes are validated first: PNG by walking the chunk structure (length, type, CRC) up to IEND,
// JPEG by its SOI/EOI markers; then the size every accepted format (PNG, JPEG, PGM/PPM, BMP, TIFF, WebP)
// declares in its header must be at most 2^26 pixels, so that no header makes OpenCV allocate gigabytes;
// other formats are refused. Every failure is one beslam::Error naming the file ("missing", "truncated ...",
// "corrupt ...", "unknown image format ...", "... more than the 67108864 the loader decodes", "cannot decode ...").
// The SDK component beslam::image_io (OpenCV imgcodecs and zlib), not beslam::formats: link that to use it.
#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace beslam::formats {

struct LoadedImage {
  cv::Mat gray;   // CV_8UC1 (colour images are converted, 16-bit images scaled by 1/256)
  cv::Mat color;  // CV_8UC3 BGR if want_color and the file has colour; empty otherwise
};

LoadedImage loadImage(const std::string& path, bool want_color);

// Throws beslam::Error naming `path` unless `bytes` is a complete PNG stream (signature, chunks with valid
// lengths and CRCs, IHDR first, IEND present).
void checkPng(const std::string& path, const std::string& bytes);

// Width and height as the file's header declares them, after loadImage's checks that need no decoding (the
// same formats and size limit, a PNG's chunks and a JPEG's end marker whole); throws like loadImage. The
// pixels are not decoded: corrupt image data is found when the frame itself is loaded.
cv::Size readImageSize(const std::string& path);

}  // namespace beslam::formats
