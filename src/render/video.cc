#include "aia/render/video.h"

#include <cstdio>
#include <filesystem>
#include <opencv2/videoio.hpp>
#include <stdexcept>

#include "aia/core/check.h"
#include "aia/core/io.h"

namespace aia {

Mp4Writer::Mp4Writer(const std::string& path, int width, int height, double fps)
    : path_(path), width_(width), height_(height) {
  AIA_CHECK(width > 0 && height > 0 && fps > 0.0);
  CheckReplaceableFile(path);
  const std::filesystem::path p(path);
  // OpenCV picks the container from the extension: keep .mp4 last.
  tmp_ =
      (p.parent_path() / ("." + p.stem().string() + ".partial.mp4")).string();
  const cv::Size size(width, height);
  for (const char* fourcc : {"avc1", "mp4v"}) {
    writer_ = std::make_unique<cv::VideoWriter>();
    const int code =
        cv::VideoWriter::fourcc(fourcc[0], fourcc[1], fourcc[2], fourcc[3]);
    if (writer_->open(tmp_, cv::CAP_FFMPEG, code, fps, size, true) &&
        writer_->isOpened()) {
      codec_ = fourcc;
      return;
    }
  }
  writer_.reset();
  std::remove(tmp_.c_str());
  throw std::runtime_error("cannot open an MP4 video for writing at " + path);
}

Mp4Writer::~Mp4Writer() {
  if (writer_) {
    writer_->release();
    std::remove(tmp_.c_str());
  }
}

void Mp4Writer::Write(const cv::Mat& bgr) {
  AIA_CHECK(writer_ != nullptr);
  AIA_CHECK(bgr.type() == CV_8UC3 && bgr.cols == width_ && bgr.rows == height_);
  writer_->write(bgr);
  ++frames_;
}

void Mp4Writer::Commit() {
  AIA_CHECK(writer_ != nullptr);
  writer_->release();
  writer_.reset();
  std::error_code ec;
  std::filesystem::rename(tmp_, path_, ec);
  if (ec) {
    std::remove(tmp_.c_str());
    throw std::runtime_error("cannot move the video to " + path_ + ": " +
                             ec.message());
  }
}

}  // namespace aia
