// world/media.h: loads the media plugin at the first call and forwards.
#include "aia/world/media.h"

#include "aia/core/check.h"
#include "aia/core/plugin.h"
#include "media_table.h"

#ifndef AIA_MEDIA_PLUGIN
#error "AIA_MEDIA_PLUGIN: the plugin's path, set by CMakeLists.txt"
#endif

namespace aia {
namespace {

const MediaTable& Media() {
  static const MediaTable* const table =
      static_cast<const MediaTable*>(LoadPluginTable(
          AIA_MEDIA_PLUGIN, kMediaTableSymbol,
          PluginHeader{kMediaTableVersion, sizeof(MediaTable)},
          "OpenCV's image and video codecs: map images, frames and videos "
          "need them"));
  return *table;
}

}  // namespace

bool DecodeGray(const std::string& bytes, int* cols, int* rows,
                std::vector<std::uint8_t>* pixels) {
  return Media().decode_gray(bytes, cols, rows, pixels);
}

std::string EncodePng(const std::uint8_t* bgr, int width, int height,
                      std::size_t stride) {
  std::string png;
  if (!Media().encode_png(bgr, width, height, stride, &png)) png.clear();
  return png;
}

std::unique_ptr<VideoFile> VideoFile::Open(const std::string& path, int width,
                                           int height, double fps,
                                           std::string* codec) {
  void* handle = Media().open_video(path, width, height, fps, codec);
  if (!handle) return nullptr;
  return std::unique_ptr<VideoFile>(new VideoFile(handle, width, height));
}

VideoFile::~VideoFile() { Close(); }

void VideoFile::Write(const std::uint8_t* bgr, std::size_t stride) {
  AIA_CHECK(handle_ != nullptr);
  // The size is the one opened with: Mp4Writer checks each frame.
  Media().write_video(handle_, bgr, width_, height_, stride);
}

void VideoFile::Close() {
  if (handle_) Media().close_video(handle_);
  handle_ = nullptr;
}

int CountVideoFrames(const std::string& path) {
  return Media().count_frames(path);
}

}  // namespace aia
