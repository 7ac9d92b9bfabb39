#include "beslam/formats/image_io.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"

namespace beslam::formats {
namespace {

constexpr std::array<unsigned char, 8> kPngSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};

std::uint32_t readBigEndian32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | std::uint32_t(p[3]);
}

bool hasPngSignature(const std::string& bytes) {
  return bytes.size() >= kPngSignature.size() &&
         std::equal(kPngSignature.begin(), kPngSignature.end(), reinterpret_cast<const unsigned char*>(bytes.data()));
}

bool hasJpegStart(const std::string& bytes) {
  return bytes.size() >= 3 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
         static_cast<unsigned char>(bytes[1]) == 0xD8 && static_cast<unsigned char>(bytes[2]) == 0xFF;
}

void checkJpeg(const std::string& path, const std::string& bytes) {
  std::size_t end = bytes.size();
  while (end > 0 && bytes[end - 1] == '\0') --end;  // some writers pad with zeros after EOI
  if (end < 4 || static_cast<unsigned char>(bytes[end - 2]) != 0xFF ||
      static_cast<unsigned char>(bytes[end - 1]) != 0xD9)
    throwAt(path, "truncated JPEG image (no end-of-image marker, " + std::to_string(bytes.size()) + " bytes)");
}

// The largest image the loader decodes: 2^26 pixels (8192 x 8192). A header claiming more is refused before
// OpenCV allocates for it (a 60-byte JPEG can claim 65,000 x 12,000 pixels: 2.4 GB).
constexpr std::uint64_t kMaxImagePixels = std::uint64_t(1) << 26;

std::uint32_t readLittleEndian32(const unsigned char* p) {
  return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) | (std::uint32_t(p[3]) << 24);
}
std::uint32_t readLittleEndian24(const unsigned char* p) {
  return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16);
}
std::uint32_t readLittleEndian16(const unsigned char* p) { return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8); }
std::uint32_t readBigEndian16(const unsigned char* p) { return (std::uint32_t(p[0]) << 8) | std::uint32_t(p[1]); }

struct DeclaredSize {
  std::uint64_t width = 0, height = 0;
};

// JPEG: the first frame header (SOF0-SOF15 but DHT, JPG and DAC) before the scan.
std::optional<DeclaredSize> jpegSize(const unsigned char* d, std::size_t size) {
  std::size_t pos = 2;
  while (pos + 4 <= size) {
    if (d[pos] != 0xFF) return std::nullopt;
    const unsigned char marker = d[pos + 1];
    if (marker == 0xFF) {  // fill byte
      ++pos;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // no length
      pos += 2;
      continue;
    }
    if (marker == 0xDA || marker == 0xD9) return std::nullopt;  // scan or end before any frame header
    const std::size_t length = readBigEndian16(d + pos + 2);
    const bool frame = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame) {
      if (length < 7 || pos + 9 > size) return std::nullopt;
      return DeclaredSize{readBigEndian16(d + pos + 7), readBigEndian16(d + pos + 5)};
    }
    pos += 2 + length;
  }
  return std::nullopt;
}

// PGM / PPM / PBM: "P1".."P6", then width and height as text, with "#" comments.
std::optional<DeclaredSize> pnmSize(const unsigned char* d, std::size_t size) {
  std::size_t pos = 2;
  std::uint64_t values[2] = {0, 0};
  for (std::uint64_t& value : values) {
    while (pos < size && (std::isspace(d[pos]) || d[pos] == '#')) {
      if (d[pos] == '#')
        while (pos < size && d[pos] != '\n') ++pos;
      else
        ++pos;
    }
    if (pos >= size || !std::isdigit(d[pos])) return std::nullopt;
    for (; pos < size && std::isdigit(d[pos]) && value <= kMaxImagePixels; ++pos) value = value * 10 + (d[pos] - '0');
  }
  return DeclaredSize{values[0], values[1]};
}

// BMP: the info header's width and height (negative height: rows top-down); the 12-byte core header has 16-bit ones.
std::optional<DeclaredSize> bmpSize(const unsigned char* d, std::size_t size) {
  if (size < 26) return std::nullopt;
  if (readLittleEndian32(d + 14) == 12) return DeclaredSize{readLittleEndian16(d + 18), readLittleEndian16(d + 20)};
  const auto width = static_cast<std::int32_t>(readLittleEndian32(d + 18));
  const auto height = static_cast<std::int32_t>(readLittleEndian32(d + 22));
  return DeclaredSize{static_cast<std::uint64_t>(std::abs(std::int64_t(width))),
                      static_cast<std::uint64_t>(std::abs(std::int64_t(height)))};
}

// WebP: the simple lossy ("VP8 "), lossless ("VP8L") or extended ("VP8X") header after "RIFF....WEBP".
std::optional<DeclaredSize> webpSize(const unsigned char* d, std::size_t size) {
  if (size < 30) return std::nullopt;
  if (std::equal(d + 12, d + 16, "VP8 "))
    return DeclaredSize{readLittleEndian16(d + 26) & 0x3FFFu, readLittleEndian16(d + 28) & 0x3FFFu};
  if (std::equal(d + 12, d + 16, "VP8L")) {
    const std::uint32_t bits = readLittleEndian32(d + 21);
    return DeclaredSize{(bits & 0x3FFFu) + 1, ((bits >> 14) & 0x3FFFu) + 1};
  }
  if (std::equal(d + 12, d + 16, "VP8X"))
    return DeclaredSize{readLittleEndian24(d + 24) + 1u, readLittleEndian24(d + 27) + 1u};
  return std::nullopt;
}

// TIFF: ImageWidth (256) and ImageLength (257) in the first image file directory, either byte order.
std::optional<DeclaredSize> tiffSize(const unsigned char* d, std::size_t size) {
  if (size < 8) return std::nullopt;
  const bool little = d[0] == 'I';
  const auto u16 = [&](std::size_t at) -> std::uint32_t {
    return little ? std::uint32_t(d[at]) | (std::uint32_t(d[at + 1]) << 8) : readBigEndian16(d + at);
  };
  const auto u32 = [&](std::size_t at) { return little ? readLittleEndian32(d + at) : readBigEndian32(d + at); };
  const std::size_t directory = u32(4);
  if (directory > size || size - directory < 2) return std::nullopt;
  const std::size_t entries = u16(directory);
  DeclaredSize declared;
  for (std::size_t i = 0; i < entries; ++i) {
    const std::size_t entry = directory + 2 + 12 * i;
    if (entry + 12 > size) return std::nullopt;
    const std::uint32_t tag = u16(entry), type = u16(entry + 2);
    if (tag != 256 && tag != 257) continue;
    const std::uint64_t value = type == 3 ? u16(entry + 8) : type == 4 ? u32(entry + 8) : 0;  // SHORT or LONG
    (tag == 256 ? declared.width : declared.height) = value;
  }
  return declared;
}

// The width and height an image file declares in its header, for the formats the datasets take (PNG, JPEG,
// PGM/PPM, BMP, TIFF, WebP); refuses a size that is missing, zero or above kMaxImagePixels, and any other
// format (OpenCV would decode a few more, with no size known before it allocates).
cv::Size checkDeclaredSize(const std::string& path, const std::string& bytes) {
  const auto* d = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t size = bytes.size();
  const auto starts = [&](const char* magic, std::size_t n) { return size >= n && std::equal(d, d + n, magic); };
  std::optional<DeclaredSize> declared;
  const char* format = nullptr;
  if (hasPngSignature(bytes)) {
    format = "PNG";
    if (size >= 24) declared = DeclaredSize{readBigEndian32(d + 16), readBigEndian32(d + 20)};
  } else if (hasJpegStart(bytes)) {
    format = "JPEG";
    declared = jpegSize(d, size);
  } else if (size >= 2 && d[0] == 'P' && d[1] >= '1' && d[1] <= '6') {
    format = "PGM/PPM";
    declared = pnmSize(d, size);
  } else if (starts("BM", 2)) {
    format = "BMP";
    declared = bmpSize(d, size);
  } else if (starts("II*\0", 4) || starts("MM\0*", 4)) {
    format = "TIFF";
    declared = tiffSize(d, size);
  } else if (starts("RIFF", 4) && size >= 12 && std::equal(d + 8, d + 12, "WEBP")) {
    format = "WebP";
    declared = webpSize(d, size);
  } else {
    throwAt(path, "unknown image format (accepted: PNG, JPEG, PGM/PPM, BMP, TIFF, WebP)");
  }
  if (!declared || declared->width == 0 || declared->height == 0)
    throwAt(path, std::string("corrupt ") + format + " image (no image size in its header)");
  if (declared->width > kMaxImagePixels || declared->height > kMaxImagePixels ||
      declared->width * declared->height > kMaxImagePixels)
    throwAt(path, std::string(format) + " image of " + std::to_string(declared->width) + "x" +
                      std::to_string(declared->height) + " pixels, more than the " + std::to_string(kMaxImagePixels) +
                      " the loader decodes");
  return {static_cast<int>(declared->width), static_cast<int>(declared->height)};
}

void requireFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throwAt(path, "missing image");
  if (!std::filesystem::is_regular_file(path, ec)) throwAt(path, "image path is not a regular file");
}

}  // namespace

void checkPng(const std::string& path, const std::string& bytes) {
  if (!hasPngSignature(bytes)) throwAt(path, "not a PNG file (bad signature)");
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t size = bytes.size();
  std::size_t pos = kPngSignature.size();
  bool first = true, seen_idat = false;
  while (true) {
    if (pos + 8 > size)
      throwAt(path, "truncated PNG image (ends after " + std::to_string(size) + " bytes, before IEND)");
    const std::uint32_t length = readBigEndian32(data + pos);
    const std::string type(reinterpret_cast<const char*>(data + pos + 4), 4);
    if (length > 0x7FFFFFFFu)
      throwAt(path, "corrupt PNG image (chunk length too large at byte " + std::to_string(pos) + ")");
    for (char c : type)
      if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z')))
        throwAt(path, "corrupt PNG image (bad chunk type at byte " + std::to_string(pos) + ")");
    if (first && (type != "IHDR" || length != 13)) throwAt(path, "corrupt PNG image (IHDR is not the first chunk)");
    first = false;
    if (size - pos - 8 < std::size_t(length) + 4)
      throwAt(path, "truncated PNG image (chunk " + type + " at byte " + std::to_string(pos) +
                        " runs past the end of the " + std::to_string(size) + "-byte file)");
    const uLong crc = crc32(crc32(0L, Z_NULL, 0), data + pos + 4, static_cast<uInt>(length) + 4);
    if (crc != readBigEndian32(data + pos + 8 + length))
      throwAt(path, "corrupt PNG image (CRC mismatch in chunk " + type + " at byte " + std::to_string(pos) + ")");
    if (type == "IDAT") seen_idat = true;
    pos += std::size_t(length) + 12;
    if (type == "IEND") break;
  }
  if (!seen_idat) throwAt(path, "corrupt PNG image (no IDAT chunk)");
}

namespace {

// The file's bytes after every check that needs no decoding (present, not empty, a PNG's chunks and a JPEG's
// end marker whole, a known format whose header declares a size the loader takes); `declared`, when given,
// receives that size.
std::string readCheckedImage(const std::string& path, cv::Size* declared = nullptr) {
  requireFile(path);
  std::string bytes = readFile(path);
  if (bytes.empty()) throwAt(path, "truncated image (empty file)");
  if (hasPngSignature(bytes))
    checkPng(path, bytes);
  else if (hasJpegStart(bytes))
    checkJpeg(path, bytes);
  const cv::Size size = checkDeclaredSize(path, bytes);
  if (declared) *declared = size;
  return bytes;
}

}  // namespace

LoadedImage loadImage(const std::string& path, bool want_color) {
  const std::string bytes = readCheckedImage(path);

  cv::Mat decoded;
  try {
    decoded = cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data())),
                           cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throwAt(path, std::string("cannot decode image: ") + e.what());
  }
  if (decoded.empty()) throwAt(path, "cannot decode image (unknown format or corrupt data)");
  if (decoded.depth() == CV_16U)
    decoded.convertTo(decoded, CV_8U, 1.0 / 256.0);
  else if (decoded.depth() != CV_8U)
    throwAt(path, "unsupported image depth (expected 8 or 16 bits)");

  LoadedImage image;
  switch (decoded.channels()) {
    case 1:
      image.gray = decoded;
      break;
    case 2:
      cv::extractChannel(decoded, image.gray, 0);
      break;
    case 3:
      cv::cvtColor(decoded, image.gray, cv::COLOR_BGR2GRAY);
      if (want_color) image.color = decoded;
      break;
    case 4:
      cv::cvtColor(decoded, image.gray, cv::COLOR_BGRA2GRAY);
      if (want_color) cv::cvtColor(decoded, image.color, cv::COLOR_BGRA2BGR);
      break;
    default:
      throwAt(path, "unsupported image with " + std::to_string(decoded.channels()) + " channels");
  }
  return image;
}

cv::Size readImageSize(const std::string& path) {
  cv::Size declared;
  readCheckedImage(path, &declared);
  return declared;
}

}  // namespace beslam::formats
