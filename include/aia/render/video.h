// An H.264 MP4 written through OpenCV's FFMPEG backend (world/media.h), to a
// temporary name in the same directory and renamed into place by Commit(),
// so an interrupted render never leaves a truncated video under the final name.
#ifndef AIA_RENDER_VIDEO_H_
#define AIA_RENDER_VIDEO_H_

#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "aia/world/media.h"

namespace aia {

class Mp4Writer {
 public:
  // Opens `path` (its directory must exist) for width x height frames at
  // `fps`. H.264 ('avc1') when FFMPEG has an encoder for it, else MPEG-4
  // Part 2 ('mp4v'). Throws std::runtime_error when neither opens.
  Mp4Writer(const std::string& path, int width, int height, double fps);
  ~Mp4Writer();
  Mp4Writer(const Mp4Writer&) = delete;
  Mp4Writer& operator=(const Mp4Writer&) = delete;

  // Appends a BGR frame of the size given at construction.
  void Write(const cv::Mat& bgr);
  // Finishes the file and renames it to `path`.
  void Commit();

  int frames() const { return frames_; }
  const std::string& codec() const { return codec_; }  // "avc1" or "mp4v"

 private:
  std::string path_, tmp_, codec_;
  int width_, height_;
  int frames_ = 0;
  std::unique_ptr<VideoFile> writer_;
};

}  // namespace aia

#endif  // AIA_RENDER_VIDEO_H_
