// Writing 8-bit BGR images (OpenCV's cv::Mat layout) as PNG files with libpng.
//
// Why not cv::imwrite: OpenCV's imgcodecs module pulls ~120 shared libraries (GDAL,
// DICOM, HEIF, ...) into every program that links it, and loading them is most of a
// `tactile` command's start-up (0.1 s of CPU per process, measured 2026-11-24): a sweep
// of short trials paid it once per process. The `tactile` programs only ever write PNG.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace tactile_common {

/// Writes `height` rows of `width` BGR pixels (3 bytes each; row r starts at
/// `bgr + r * stride_bytes`) to `path` as an 8-bit RGB PNG. Throws std::runtime_error
/// naming the file and the reason (cannot open, libpng error, short write).
void write_png_bgr(const std::string& path, const uint8_t* bgr, int width, int height,
                   std::size_t stride_bytes);

}  // namespace tactile_common
