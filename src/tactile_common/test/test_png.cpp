// write_png_bgr against libpng's simplified reader (a separate decoding path) and its errors.
#include <gtest/gtest.h>
#include <png.h>

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_common/png.hpp"

namespace fs = std::filesystem;

namespace {

std::vector<uint8_t> read_rgb(const std::string& path, int& w, int& h) {
  png_image im{};
  im.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&im, path.c_str())) throw std::runtime_error(im.message);
  im.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> px(PNG_IMAGE_SIZE(im));
  if (!png_image_finish_read(&im, nullptr, px.data(), 0, nullptr)) throw std::runtime_error(im.message);
  w = static_cast<int>(im.width);
  h = static_cast<int>(im.height);
  return px;
}

}  // namespace

TEST(Png, WritesBgrRowsWithStrideAsRgb) {
  const fs::path dir = fs::temp_directory_path() / ("tactile_png_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // 3 x 2 pixels, rows padded to 12 bytes; pixel (x, y) = BGR (10x + y, 100 + x, 200 + y).
  const int W = 3, H = 2;
  const std::size_t stride = 12;
  std::vector<uint8_t> bgr(stride * H, 0xEE);
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      uint8_t* p = bgr.data() + y * stride + x * 3;
      p[0] = static_cast<uint8_t>(10 * x + y);
      p[1] = static_cast<uint8_t>(100 + x);
      p[2] = static_cast<uint8_t>(200 + y);
    }
  }
  const std::string path = (dir / "a.png").string();
  tactile_common::write_png_bgr(path, bgr.data(), W, H, stride);
  int w = 0, h = 0;
  const auto rgb = read_rgb(path, w, h);
  ASSERT_EQ(w, W);
  ASSERT_EQ(h, H);
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const uint8_t* q = rgb.data() + (y * W + x) * 3;
      EXPECT_EQ(q[0], 200 + y) << x << "," << y;  // R = B-G-R's third byte
      EXPECT_EQ(q[1], 100 + x) << x << "," << y;
      EXPECT_EQ(q[2], 10 * x + y) << x << "," << y;
    }
  }
  fs::remove_all(dir);
}

TEST(Png, ErrorsNameTheFileAndReason) {
  const uint8_t px[3] = {1, 2, 3};
  try {
    tactile_common::write_png_bgr("/nonexistent-dir/x.png", px, 1, 1, 3);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(tactile_common::write_png_bgr("x.png", px, 1, 1, 2), std::runtime_error);  // stride < 3 w
  EXPECT_THROW(tactile_common::write_png_bgr("x.png", px, 0, 1, 3), std::runtime_error);
}
