// The media plugin (src/world/media_table.h): OpenCV's image codecs and its
// FFMPEG video backend. Nothing of aia is linked here but the table's
// header; an OpenCV exception ends as the function's failure value.
#include <sched.h>

#include <new>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <stdexcept>

#include "../media_table.h"

namespace {

cv::Mat Wrap(const std::uint8_t* bgr, int width, int height,
             std::size_t stride) {
  return cv::Mat(height, width, CV_8UC3, const_cast<std::uint8_t*>(bgr),
                 stride);
}

// x264 sizes its thread pool from the CPUs the thread that opens it may run
// on (1.5 threads per CPU), and holds frames for each thread beside its 40
// frames of look-ahead: the memory of a video of W x H pixels grew with the
// machine's cores. The encoder is opened (and its threads start) on at most
// kEncoderCpus of them, so that its memory is the same everywhere
// (docs/hardening.md, Memory of a render); the caller's own affinity is
// restored.
constexpr int kEncoderCpus = 2;

class FewerCpus {
 public:
  FewerCpus() {
    if (::sched_getaffinity(0, sizeof(saved_), &saved_) != 0) return;
    if (CPU_COUNT(&saved_) <= kEncoderCpus) return;
    cpu_set_t few;
    CPU_ZERO(&few);
    int n = 0;
    for (int c = 0; c < CPU_SETSIZE && n < kEncoderCpus; ++c)
      if (CPU_ISSET(c, &saved_)) {
        CPU_SET(c, &few);
        ++n;
      }
    changed_ = ::sched_setaffinity(0, sizeof(few), &few) == 0;
  }
  ~FewerCpus() {
    if (changed_) ::sched_setaffinity(0, sizeof(saved_), &saved_);
  }
  FewerCpus(const FewerCpus&) = delete;
  FewerCpus& operator=(const FewerCpus&) = delete;

 private:
  cpu_set_t saved_;
  bool changed_ = false;
};

aia::MediaTable MakeTable() {
  aia::MediaTable t;
  t.decode_gray = [](const std::string& bytes, int* cols, int* rows,
                     std::vector<std::uint8_t>* pixels) {
    cv::Mat img;
    try {
      const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8U,
                        const_cast<char*>(bytes.data()));
      img = cv::imdecode(raw, cv::IMREAD_GRAYSCALE);
      if (img.empty()) return false;
      if (img.depth() != CV_8U) img.convertTo(img, CV_8U, 1.0 / 256.0);
    } catch (const cv::Exception&) {
      return false;
    }
    *cols = img.cols;
    *rows = img.rows;
    pixels->assign(img.begin<std::uint8_t>(), img.end<std::uint8_t>());
    return true;
  };
  t.encode_png = [](const std::uint8_t* bgr, int width, int height,
                    std::size_t stride, std::string* out) {
    std::vector<unsigned char> png;
    try {
      if (!cv::imencode(".png", Wrap(bgr, width, height, stride), png))
        return false;
    } catch (const cv::Exception&) {
      return false;
    }
    out->assign(png.begin(), png.end());
    return true;
  };
  t.open_video = [](const std::string& path, int width, int height, double fps,
                    std::string* codec) -> void* {
    for (const char* fourcc : {"avc1", "mp4v"}) {
      auto* writer = new cv::VideoWriter();
      const int code =
          cv::VideoWriter::fourcc(fourcc[0], fourcc[1], fourcc[2], fourcc[3]);
      bool opened = false;
      try {
        const FewerCpus few;
        opened = writer->open(path, cv::CAP_FFMPEG, code, fps,
                              cv::Size(width, height), true) &&
                 writer->isOpened();
      } catch (const cv::Exception& e) {
        delete writer;
        if (e.code == cv::Error::StsNoMem) throw std::bad_alloc();
        continue;
      }
      if (opened) {
        *codec = fourcc;
        return writer;
      }
      delete writer;
    }
    return nullptr;
  };
  t.write_video = [](void* video, const std::uint8_t* bgr, int width,
                     int height, std::size_t stride) {
    // OpenCV's own exception text is several lines with its source path:
    // running out of memory is std::bad_alloc (aia's "out of memory"
    // line), anything else one line.
    try {
      static_cast<cv::VideoWriter*>(video)->write(
          Wrap(bgr, width, height, stride));
    } catch (const cv::Exception& e) {
      if (e.code == cv::Error::StsNoMem) throw std::bad_alloc();
      throw std::runtime_error("the video encoder failed: " + e.msg);
    }
  };
  t.close_video = [](void* video) {
    auto* writer = static_cast<cv::VideoWriter*>(video);
    writer->release();
    delete writer;
  };
  t.count_frames = [](const std::string& path) {
    cv::VideoCapture probe(path, cv::CAP_FFMPEG);
    if (!probe.isOpened()) return -1;
    return static_cast<int>(probe.get(cv::CAP_PROP_FRAME_COUNT));
  };
  return t;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const void*
aia_media_table() {
  static const aia::MediaTable table = MakeTable();
  return &table;
}
