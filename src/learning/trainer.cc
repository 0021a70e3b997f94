// learning/trainer.h's file names and log text; the training itself is in
// the plugin (src/learning/torch/trainer.cc), reached through
// src/learning/torch_backend.cc.
#include "aia/learning/trainer.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace aia {

std::string ValidationText(const EpochLog& e) {
  if (std::isnan(e.val_loss)) return "val: none";
  char buf[96];
  if (std::isnan(e.val_acc_useful)) {
    std::snprintf(buf, sizeof buf, "val loss %.4f acc %.3f (useful: none)",
                  e.val_loss, e.val_acc);
  } else {
    std::snprintf(buf, sizeof buf, "val loss %.4f acc %.3f (useful %.3f)",
                  e.val_loss, e.val_acc, e.val_acc_useful);
  }
  return buf;
}

std::string CheckpointPath(const std::string& out) { return out + ".ckpt"; }

std::string TrainLogPath(const std::string& out) {
  std::string base = out;
  if (base.size() > 3 && base.compare(base.size() - 3, 3, ".pt") == 0)
    base.resize(base.size() - 3);
  return base + ".train.csv";
}

}  // namespace aia
