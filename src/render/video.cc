#include "aia/render/video.h"

#include <sys/statvfs.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "aia/core/check.h"
#include "aia/core/io.h"

namespace aia {

namespace {

// Why the finished video at `file` is not whole (FFmpeg's writer reports no
// errors: a full disk leaves a cut file without its index), or "".
std::string VideoDamage(const std::string& file, int frames) {
  const int n = CountVideoFrames(file);
  if (n < 0) return "the encoder left an unreadable file";
  if (n != frames)
    return "the encoder wrote " + std::to_string(static_cast<long>(n)) +
           " of " + std::to_string(frames) + " frames";
  return "";
}

// Whether the file system of `dir` is (nearly) full: what cut the video
// short, when the encoder does not say.
bool NoSpaceLeft(const std::string& dir) {
  struct statvfs st;
  if (::statvfs(dir.empty() ? "." : dir.c_str(), &st) != 0) return false;
  return static_cast<double>(st.f_bavail) * st.f_frsize < 1024.0 * 1024.0;
}

}  // namespace

Mp4Writer::Mp4Writer(const std::string& path, int width, int height, double fps)
    : path_(path), width_(width), height_(height) {
  AIA_CHECK(width > 0 && height > 0 && fps > 0.0);
  CheckReplaceableFile(path);
  // FFmpeg's own log lines (OpenCV passes them to stderr) are not aia's
  // errors: aia checks the finished file and reports on one line. Set before
  // OpenCV's FFmpeg backend starts; a user's own setting is kept.
  ::setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", /*overwrite=*/0);
  // OpenCV picks the container from the extension: keep .mp4 last
  // (.STEM.tmp.PID.mp4, which a later job removes once PID is gone).
  tmp_ = TemporaryPath(path, /*keep_extension=*/true);
  writer_ = VideoFile::Open(tmp_, width, height, fps, &codec_);
  if (writer_) return;
  std::remove(tmp_.c_str());
  throw std::runtime_error("cannot open an MP4 video for writing at " + path);
}

Mp4Writer::~Mp4Writer() {
  if (writer_) {
    writer_->Close();
    std::remove(tmp_.c_str());
  }
}

void Mp4Writer::Write(const cv::Mat& bgr) {
  AIA_CHECK(writer_ != nullptr);
  AIA_CHECK(bgr.type() == CV_8UC3 && bgr.cols == width_ && bgr.rows == height_);
  writer_->Write(bgr.data, bgr.step);
  ++frames_;
}

void Mp4Writer::Commit() {
  AIA_CHECK(writer_ != nullptr);
  writer_->Close();
  writer_.reset();
  if (std::string damage = VideoDamage(tmp_, frames_); !damage.empty()) {
    const std::string dir = std::filesystem::path(tmp_).parent_path().string();
    if (NoSpaceLeft(dir)) damage = std::strerror(ENOSPC);
    std::remove(tmp_.c_str());
    ThrowCannotWrite(path_, damage);
  }
  std::error_code ec;
  std::filesystem::rename(tmp_, path_, ec);
  if (ec) {
    std::remove(tmp_.c_str());
    ThrowCannotWrite(path_, ec.message());
  }
}

}  // namespace aia
