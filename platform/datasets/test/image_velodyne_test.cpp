#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "beslam/datasets/image_io.hpp"
#include "beslam/datasets/velodyne.hpp"
#include "test_util.hpp"

namespace beslam::datasets {
namespace {

using test::TempDir;

TEST(Velodyne, RoundTripAndErrors) {
  TempDir dir;
  const std::string path = dir / "000000.bin";
  const std::vector<float> xyzr = {1.5f, -2.f, 0.25f, 0.9f, 10.f, 0.f, -1.7f, 0.f};
  writeVelodyneBin(path, xyzr);
  EXPECT_EQ(readVelodyneBin(path), xyzr);
  EXPECT_EQ(std::filesystem::file_size(path), 32u);

  test::truncateFile(path, 20);
  EXPECT_BESLAM_ERROR(readVelodyneBin(path), path, "truncated", "20 bytes");
  EXPECT_BESLAM_ERROR(readVelodyneBin(dir / "missing.bin"), dir / "missing.bin", "missing");
  EXPECT_BESLAM_ERROR(writeVelodyneBin(path, {1.f, 2.f, 3.f}), path, "multiple of 4");
  test::truncateFile(path, 0);
  EXPECT_TRUE(readVelodyneBin(path).empty());  // an empty scan is valid
}

TEST(ImageIo, GrayAndColour) {
  TempDir dir;
  test::writePng(dir / "gray.png", 37, 21, 1, 3);
  test::writePng(dir / "color.png", 37, 21, 3, 5);
  const LoadedImage gray = loadImage(dir / "gray.png", true);
  EXPECT_EQ(gray.gray.type(), CV_8UC1);
  EXPECT_TRUE(gray.color.empty());  // no colour in the file
  EXPECT_EQ(cv::norm(gray.gray, test::pattern(37, 21, 1, 3), cv::NORM_INF), 0);

  const LoadedImage color = loadImage(dir / "color.png", true);
  ASSERT_EQ(color.color.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(color.color, test::pattern(37, 21, 3, 5), cv::NORM_INF), 0);
  cv::Mat expected_gray;
  cv::cvtColor(test::pattern(37, 21, 3, 5), expected_gray, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(color.gray, expected_gray, cv::NORM_INF), 0);
  EXPECT_TRUE(loadImage(dir / "color.png", false).color.empty());
  EXPECT_EQ(readImageSize(dir / "color.png"), cv::Size(37, 21));
}

TEST(ImageIo, SixteenBitAndJpeg) {
  TempDir dir;
  cv::Mat deep(10, 12, CV_16UC1, cv::Scalar(256 * 200 + 17));
  ASSERT_TRUE(cv::imwrite(dir / "deep.png", deep));
  const LoadedImage image = loadImage(dir / "deep.png", false);
  EXPECT_EQ(image.gray.type(), CV_8UC1);
  EXPECT_EQ(image.gray.at<unsigned char>(3, 4), 200);

  ASSERT_TRUE(cv::imwrite(dir / "a.jpg", test::pattern(64, 48, 3)));
  EXPECT_EQ(loadImage(dir / "a.jpg", true).color.size(), cv::Size(64, 48));
  EXPECT_EQ(readImageSize(dir / "a.jpg"), cv::Size(64, 48));
  test::truncateFile(dir / "a.jpg", std::filesystem::file_size(dir / "a.jpg") / 2);
  EXPECT_BESLAM_ERROR(loadImage(dir / "a.jpg", false), dir / "a.jpg", "truncated JPEG");
  EXPECT_BESLAM_ERROR(readImageSize(dir / "a.jpg"), dir / "a.jpg", "truncated JPEG");
}

TEST(ImageIo, MissingUnreadableAndTruncated) {
  TempDir dir;
  EXPECT_BESLAM_ERROR(loadImage(dir / "none.png", false), dir / "none.png", "missing image");
  EXPECT_BESLAM_ERROR(readImageSize(dir / "none.png"), dir / "none.png", "missing image");
  test::writeText(dir / "text.png", "this is not an image");
  EXPECT_BESLAM_ERROR(loadImage(dir / "text.png", false), dir / "text.png", "unknown image format", "PNG, JPEG");
  EXPECT_BESLAM_ERROR(readImageSize(dir / "text.png"), dir / "text.png", "unknown image format", "PNG, JPEG");
  test::writeText(dir / "empty.png", "");
  EXPECT_BESLAM_ERROR(loadImage(dir / "empty.png", false), dir / "empty.png", "empty");

  // Cut at many points: every prefix is reported as truncated (never a silently partial image).
  test::writePng(dir / "full.png", 200, 120, 1);
  const std::string bytes = test::readBytes(dir / "full.png");
  for (std::size_t keep :
       {std::size_t(8), std::size_t(30), bytes.size() / 3, bytes.size() / 2, bytes.size() - 13, bytes.size() - 1}) {
    const std::string path = dir / ("cut" + std::to_string(keep) + ".png");
    test::writeText(path, bytes.substr(0, keep));
    EXPECT_BESLAM_ERROR(loadImage(path, false), path, "truncated PNG");
  }
  // A flipped byte inside the image data is caught by the chunk CRC.
  std::string corrupt = bytes;
  corrupt[bytes.size() / 2] = static_cast<char>(corrupt[bytes.size() / 2] ^ 0x5A);
  test::writeText(dir / "corrupt.png", corrupt);
  EXPECT_BESLAM_ERROR(loadImage(dir / "corrupt.png", false), dir / "corrupt.png", "CRC mismatch");
  EXPECT_BESLAM_ERROR(checkPng("x.png", "GIF89a"), "x.png", "not a PNG");
}

TEST(ImageIo, EveryFormatTheImageFolderTakesLoads) {
  TempDir dir;
  for (const char* name : {"a.pgm", "a.ppm", "a.bmp", "a.tiff", "a.webp"}) {
    const bool grey = std::string(name) == "a.pgm";
    ASSERT_TRUE(cv::imwrite(dir / name, test::pattern(37, 21, grey ? 1 : 3))) << name;
    EXPECT_EQ(loadImage(dir / name, true).gray.size(), cv::Size(37, 21)) << name;
    EXPECT_EQ(readImageSize(dir / name), cv::Size(37, 21)) << name;  // from the header alone
  }
}

// A header that claims a huge image is refused before OpenCV allocates for it. The JPEG is the nightly fuzz
// run's finding: 60 bytes claiming 12042 x 65496 pixels made imdecode allocate 2.4 GB.
TEST(ImageIo, AHeaderClaimingAHugeImageIsRefusedBeforeDecoding) {
  TempDir dir;
  const auto expectRefused = [&](const std::string& name, const std::string& bytes, const std::string& format) {
    test::writeText(dir / name, bytes);
    EXPECT_BESLAM_ERROR(loadImage(dir / name, false), dir / name, format + " image of", "more than the 67108864");
    EXPECT_BESLAM_ERROR(readImageSize(dir / name), dir / name, format + " image of", "more than the 67108864");
  };
  const std::string jpeg(
      "\xff\xd8\xff\xc0\x00\x11\x08\xff\xd8\x2f\x0a\x03\x01\x22\x00\x02\x11\x01\x03\x11\x01\xf8\xfa\xff\xda"
      "\x00\x0c\x03\x01\x00\x02\x11\x03\x11\x00\x1f\x00\x00\x00\x00\x47\xff\xd9",
      44);
  expectRefused("huge.jpg", jpeg, "JPEG");
  test::writePng(dir / "small.png", 4, 4, 1);
  std::string png = test::readBytes(dir / "small.png");
  png.replace(16, 8, std::string("\0\x01\x86\xa0\0\x01\x86\xa0", 8));  // IHDR: 100000 x 100000
  std::uint32_t crc = 0xFFFFFFFFu;                                     // PNG's CRC-32 of the chunk's type and data
  for (int i = 12; i < 29; ++i) {
    crc ^= static_cast<unsigned char>(png[i]);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  crc ^= 0xFFFFFFFFu;
  for (int i = 0; i < 4; ++i) png[29 + i] = static_cast<char>((crc >> (24 - 8 * i)) & 0xFF);  // a valid chunk
  expectRefused("huge.png", png, "PNG");
  expectRefused("huge.pgm", "P5\n# a comment\n100000 100000\n255\n\x01\x02", "PGM/PPM");
  ASSERT_TRUE(cv::imwrite(dir / "small.bmp", test::pattern(4, 4, 3)));
  std::string bmp = test::readBytes(dir / "small.bmp");
  bmp.replace(18, 8, std::string("\xa0\x86\x01\x00\x60\x79\xfe\xff", 8));  // 100000 x -100000 (top-down)
  expectRefused("huge.bmp", bmp, "BMP");
  const std::string tiff(
      "II*\0\x08\0\0\0\x02\0"
      "\x00\x01\x04\0\x01\0\0\0\xa0\x86\x01\x00"  // ImageWidth LONG 100000
      "\x01\x01\x03\0\x01\0\0\0\xff\xff\0\0",     // ImageLength SHORT 65535
      34);
  expectRefused("huge.tiff", tiff, "TIFF");
  const std::string webp("RIFF\x16\0\0\0WEBPVP8X\x0a\0\0\0\0\0\0\0\xff\x3f\0\xff\x3f\0", 30);  // 16384 x 16384
  expectRefused("huge.webp", webp, "WebP");
  // A header with no size at all is corrupt, not decoded.
  test::writeText(dir / "nosize.jpg", std::string("\xff\xd8\xff\xda\x00\x02\xff\xd9", 8));
  EXPECT_BESLAM_ERROR(loadImage(dir / "nosize.jpg", false), dir / "nosize.jpg", "corrupt JPEG image (no image size");
}

}  // namespace
}  // namespace beslam::datasets
