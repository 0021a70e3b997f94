// The media plugin's table (world/media.h, core/plugin.h): plain functions
// over OpenCV's codecs, implemented in src/world/media/plugin.cc.
#ifndef AIA_SRC_WORLD_MEDIA_TABLE_H_
#define AIA_SRC_WORLD_MEDIA_TABLE_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "aia/core/plugin.h"

namespace aia {

inline constexpr int kMediaTableVersion = 1;
inline constexpr const char* kMediaTableSymbol = "aia_media_table";

struct MediaTable {
  PluginHeader header{kMediaTableVersion, sizeof(MediaTable)};
  bool (*decode_gray)(const std::string& bytes, int* cols, int* rows,
                      std::vector<std::uint8_t>* pixels);
  bool (*encode_png)(const std::uint8_t* bgr, int width, int height,
                     std::size_t stride, std::string* out);
  // A video writer (opaque), or null; *codec is the codec that opened.
  void* (*open_video)(const std::string& path, int width, int height,
                      double fps, std::string* codec);
  void (*write_video)(void* video, const std::uint8_t* bgr, int width,
                      int height, std::size_t stride);
  void (*close_video)(void* video);  // releases and frees it
  int (*count_frames)(const std::string& path);
};

}  // namespace aia

#endif  // AIA_SRC_WORLD_MEDIA_TABLE_H_
