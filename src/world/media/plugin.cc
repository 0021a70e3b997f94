// The media plugin (src/world/media_table.h): OpenCV's image codecs and its
// FFMPEG video backend. Nothing of aia is linked here but the table's
// header; an OpenCV exception ends as the function's failure value.
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "../media_table.h"

namespace {

cv::Mat Wrap(const std::uint8_t* bgr, int width, int height,
             std::size_t stride) {
  return cv::Mat(height, width, CV_8UC3, const_cast<std::uint8_t*>(bgr),
                 stride);
}

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
      if (writer->open(path, cv::CAP_FFMPEG, code, fps, cv::Size(width, height),
                       true) &&
          writer->isOpened()) {
        *codec = fourcc;
        return writer;
      }
      delete writer;
    }
    return nullptr;
  };
  t.write_video = [](void* video, const std::uint8_t* bgr, int width,
                     int height, std::size_t stride) {
    static_cast<cv::VideoWriter*>(video)->write(
        Wrap(bgr, width, height, stride));
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
