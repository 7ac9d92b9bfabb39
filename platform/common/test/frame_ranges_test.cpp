#include "beslam/common/frame_ranges.hpp"

#include <gtest/gtest.h>

#include "beslam/common/error.hpp"

namespace {

// The error parseFrameRanges throws for text ("" when it parses).
std::string parseError(const std::string& text) {
  try {
    beslam::parseFrameRanges(text);
  } catch (const beslam::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(FrameRanges, ParsesNumbersAndInclusiveRanges) {
  const auto r = beslam::parseFrameRanges("520-539, 600,700 - 710");
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].first, 520);
  EXPECT_EQ(r[0].last, 539);
  EXPECT_EQ(r[1].first, 600);
  EXPECT_EQ(r[1].last, 600);
  EXPECT_EQ(r[2].first, 700);
  EXPECT_EQ(r[2].last, 710);
  EXPECT_TRUE(r[0].contains(520));
  EXPECT_TRUE(r[0].contains(539));
  EXPECT_FALSE(r[0].contains(540));
  EXPECT_FALSE(r[0].contains(519));
  EXPECT_EQ(beslam::frameRangesText(r), "520-539,600,700-710");
}

TEST(FrameRanges, BadTextIsOneErrorSayingWhatIsWrong) {
  EXPECT_NE(parseError("").find("empty entry"), std::string::npos);
  EXPECT_NE(parseError("520-539,").find("empty entry"), std::string::npos);
  EXPECT_NE(parseError("539-520").find("range 539-520 ends before it starts"), std::string::npos);
  EXPECT_NE(parseError("-5").find("'-5' is not a frame number"), std::string::npos);
  EXPECT_NE(parseError("5-").find("'5-' is not a frame number"), std::string::npos);
  EXPECT_NE(parseError("a-b").find("'a-b' is not a frame number"), std::string::npos);
  EXPECT_NE(parseError("1.5").find("'1.5' is not a frame number"), std::string::npos);
  EXPECT_NE(parseError("1-2-3").find("'1-2-3' is not a frame number"), std::string::npos);
  EXPECT_NE(parseError("9999999999999").find("is not a frame number"), std::string::npos);
  EXPECT_NE(parseError("10-20,15-30").find("range 15-30 does not come after 10-20"), std::string::npos);
  EXPECT_NE(parseError("10-20,5").find("range 5 does not come after 10-20"), std::string::npos);
}
