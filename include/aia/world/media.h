// Image and video files through OpenCV's codecs (imgcodecs, videoio). Those
// two libraries bring in about 240 shared libraries (gstreamer, ffmpeg,
// gdal), whose loading was most of a short run's start, so they sit in a
// plugin, libaia_media.so (src/world/media/, core/plugin.h), loaded at the
// first call here. Plain types only: no OpenCV in this header.
#ifndef AIA_WORLD_MEDIA_H_
#define AIA_WORLD_MEDIA_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace aia {

// An image file's bytes (any format OpenCV reads) as 8-bit gray, row-major
// (deeper images scaled to 8 bits); false when they are not an image.
bool DecodeGray(const std::string& bytes, int* cols, int* rows,
                std::vector<std::uint8_t>* pixels);

// PNG bytes of a BGR image, `stride` bytes a row; empty when the encoder
// fails.
std::string EncodePng(const std::uint8_t* bgr, int width, int height,
                      std::size_t stride);

// An MP4 file being written through FFMPEG (render/video.h's Mp4Writer adds
// the temporary name and the checks).
class VideoFile {
 public:
  // Opens `path` for width x height BGR frames at `fps` with the first codec
  // of "avc1" (H.264) and "mp4v" that FFMPEG can encode; null when neither.
  static std::unique_ptr<VideoFile> Open(const std::string& path, int width,
                                         int height, double fps,
                                         std::string* codec);
  ~VideoFile();  // releases the file (Close)
  VideoFile(const VideoFile&) = delete;
  VideoFile& operator=(const VideoFile&) = delete;

  void Write(const std::uint8_t* bgr, std::size_t stride);
  // Finishes the file; nothing can be written after.
  void Close();

 private:
  VideoFile(void* handle, int width, int height)
      : handle_(handle), width_(width), height_(height) {}
  void* handle_;
  int width_, height_;
};

// Frames in a finished video file, or -1 when FFMPEG cannot read it.
int CountVideoFrames(const std::string& path);

}  // namespace aia

#endif  // AIA_WORLD_MEDIA_H_
