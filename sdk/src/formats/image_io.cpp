#include "beslam/formats/image_io.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

LoadedImage loadImage(const std::string& path, bool want_color) {
  requireFile(path);
  const std::string bytes = readFile(path);
  if (bytes.empty()) throwAt(path, "truncated image (empty file)");
  if (hasPngSignature(bytes))
    checkPng(path, bytes);
  else if (hasJpegStart(bytes))
    checkJpeg(path, bytes);

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
  requireFile(path);
  std::ifstream in(path, std::ios::binary);
  std::string head(33, '\0');  // signature (8) + IHDR length/type (8) + width/height (8) + rest
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  if (hasPngSignature(head)) {
    if (head.size() < 24 || head.compare(12, 4, "IHDR") != 0) throwAt(path, "truncated PNG image (no IHDR)");
    const auto* d = reinterpret_cast<const unsigned char*>(head.data());
    const std::uint32_t width = readBigEndian32(d + 16), height = readBigEndian32(d + 20);
    if (width == 0 || height == 0 || width > 1u << 20 || height > 1u << 20)
      throwAt(path, "corrupt PNG image (size " + std::to_string(width) + "x" + std::to_string(height) + ")");
    return {static_cast<int>(width), static_cast<int>(height)};
  }
  return loadImage(path, false).gray.size();
}

}  // namespace beslam::formats
