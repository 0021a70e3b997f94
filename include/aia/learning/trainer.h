// `aia train` (docs/learning.md, Training): imitation of the expert by
// cross-entropy on the dataset's labels, channels rendered as batches are
// drawn. A checkpoint (model, optimizer, epoch) every epoch, so that a killed
// run resumes where it stopped (--resume) and gives the same numbers; a CSV
// log of loss and accuracy per epoch. torch stays in src/learning.
#ifndef AIA_LEARNING_TRAINER_H_
#define AIA_LEARNING_TRAINER_H_

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "aia/core/csv.h"
#include "aia/learning/network.h"

namespace aia {

struct TrainOptions {
  std::vector<std::string> data;  // dataset folders or files
  // The model file (required: no default, so that no run replaces the
  // shipped models/igbnet.pt by accident).
  std::string out;
  std::string init;  // start from this model (DAgger rounds); empty: fresh
  NetworkConfig network;
  // Message passing hops K (NetworkConfig::message_hops); -1: network's, or
  // --init's. From an --init model with fewer hops, its weights are kept and
  // the new hops start at zero (the same function).
  int message_hops = -1;
  // The reach channel over the whole workspace (ChannelParams::reach_world):
  // -1 the network's, or --init's; 0 or 1 sets it (from an --init model the
  // weights are kept: the same network reads the new channel 4).
  int reach_world = -1;
  // Channel 4 from the search points (ChannelParams::search), likewise.
  int search = -1;
  // The trail channel (ChannelParams::trail), likewise; from an --init
  // model without it, the stem's weights for it start at zero (the same
  // function).
  int trail = -1;
  // The centre (NetworkConfig::centre), likewise: -1 the network's or
  // --init's; from an --init model without one, fc1's weights for it start
  // at zero (the same function).
  int centre = -1;
  // The reach channel's decay length L in metres
  // (ChannelParams::geodesic_length): -1 the network's (5), or --init's; a
  // length sets it (from an --init model the weights are kept: the same
  // network reads the channel with the new contrast).
  double geodesic_length = -1.0;
  // The reach channel's detour length (ChannelParams::reach_detour), in
  // metres: -1 the network's (0, off), or --init's; 0 turns it off; above 0
  // sets it (from an --init model the weights are kept).
  double reach_detour = -1.0;
  // The broad reach channel's decay length (ChannelParams::reach_broad), in
  // metres: -1 the network's (0, off), or --init's; 0 turns it off; above 0
  // sets it (from an --init model without it, the stem's weights for the
  // new channel start at zero: the same function).
  double reach_broad = -1.0;
  // The second reach channel (ChannelParams::reach_second): -1 the
  // network's (off), or --init's; 0 or 1 sets it (from an --init model
  // without it, the stem's weights for the new channel start at zero).
  int reach_second = -1;
  // The neighbours channel's cap (ChannelParams::neighbour_cap): -1 the
  // network's (0, none), or --init's; 0 removes it; above 0 sets it (from an
  // --init model the weights are kept).
  int neighbour_cap = -1;
  int epochs = 20;
  int batch = 16;
  // Cosine from lr to lr_min over all epochs' T batches: batch t of them
  // takes step t / T, so the last is one step short of lr_min (5e-5 with
  // 18 samples, batch 16, one epoch; within 1e-8 of it at the recipe's
  // sizes). Kept: the shipped models were trained so.
  double lr = 1e-4;
  double lr_min = 1e-6;
  double weight_decay = 1e-5;
  // Weight of the samples whose robot had no useful work left in the
  // expert's plan (weak labels): 1 keeps them as they are, 0 masks them.
  double weak_weight = 1.0;
  // Factor on the weight of the samples where the acting policy's move
  // differs from the label (DAgger's states of the network's own mistakes;
  // the expert's own data has none): 1 keeps them as they are.
  double mistake_weight = 1.0;
  // Factor on the weight of the samples whose robot's own belief holds at
  // most kEndingTargets targets above eps (and at least one): the mission's
  // ending, where the last targets may lie far away behind walls. 1 keeps
  // them as they are.
  double ending_weight = 1.0;
  // 1: the loss is the cross-entropy among the moves valid from the robot's
  // lattice point (the moves the igbnet policy chooses among; validation
  // likewise); 0: among all four moves.
  int valid_moves = 0;
  double val_share = 0.1;  // of the worlds, held out for validation
  std::uint64_t seed = 1;
  int threads = 0;  // libtorch intra-op threads; 0: libtorch's default
  bool resume = false;
  bool progress = true;
  // For tests of --resume: return after this many epochs of this run, as a
  // killed run would (0: run them all).
  int stop_after_epochs = 0;

  // The hyperparameters, declared once for `aia train`'s flags and their
  // checks (the network's are NetworkConfig's; paths and modes are not
  // declared here).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(epochs)
                 .In(Between(0, 100000))
                 .Doc("epochs (0: no training, --init's weights written to "
                      "--out with the channel settings the flags change)"));
    a->Visit(AIA_FIELD(batch)
                 .In(Between(2, 65536))
                 .Doc("batch size (at least 2: batch norm needs two samples)"));
    a->Visit(
        AIA_FIELD(lr).In(kOpenUnit).Doc("learning rate at the start (cosine)"));
    a->Visit(AIA_FIELD(lr_min)
                 .In({0.0, 1.0, false, true})
                 .Doc("learning rate at the end (at most --lr)"));
    a->Visit(AIA_FIELD(weight_decay)
                 .In({0.0, 1.0, false, true})
                 .Doc("Adam's weight decay"));
    a->Visit(AIA_FIELD(weak_weight)
                 .In(kUnit)
                 .Doc("weight of samples whose robot had no useful work left "
                      "(0 masks them)"));
    a->Visit(AIA_FIELD(mistake_weight)
                 .In({0.0, 100.0, false, false})
                 .Doc("factor on the weight of samples where the acting "
                      "policy's move differs from the label (the acting "
                      "network's mistakes in DAgger data; 1: as the others)"));
    a->Visit(AIA_FIELD(ending_weight)
                 .In({0.0, 100.0, false, false})
                 .Doc("factor on the weight of samples whose robot's own "
                      "belief holds one or two targets above eps (a "
                      "mission's ending; 1: as the others)"));
    a->Visit(AIA_FIELD(valid_moves)
                 .In(Between(0, 1))
                 .Doc("1: the loss is the choice among the moves valid from "
                      "the robot's lattice point, as the policy chooses; 0: "
                      "among all four"));
    a->Visit(AIA_FIELD(val_share)
                 .In({0.0, 1.0, false, true})
                 .Doc("share of the worlds held out for validation"));
    a->Visit(AIA_FIELD(seed).Doc("initialization, split and shuffling"));
    a->Visit(AIA_FIELD(threads)
                 .In(Between(0, 1024))
                 .Doc("libtorch threads (0: libtorch's default, which "
                      "follows the machine's cores, or OMP_NUM_THREADS: "
                      "the weights depend on the count, so a model other "
                      "machines reproduce names it)"));
    a->Visit(AIA_FIELD(message_hops)
                 .In(Between(-1, kMaxMessageHops))
                 .Doc("K: hops of learned message passing over the "
                      "communication graph (0: none; -1, the default: "
                      "--init's, else 0; docs/learning.md, Network)"));
    a->Visit(AIA_FIELD(reach_world)
                 .In(Between(-1, 1))
                 .Doc("1: the reach channel over the whole workspace, "
                      "cropped to the window (with --init the weights are "
                      "kept); 0: over the window; -1, the default: --init's, "
                      "else 0"));
    a->Visit(AIA_FIELD(search)
                 .In(Between(-1, 1))
                 .Doc("1: the reach channel leads to each target's search "
                      "points (the robot's and its neighbours' misses; needs "
                      "--reach-world 1; with --init the weights are kept); "
                      "-1, the default: --init's, else 0"));
    a->Visit(AIA_FIELD(trail)
                 .In(Between(-1, 1))
                 .Doc("1: a last channel, the pixel the robot came from "
                      "(with --init the new input starts at zero weight); "
                      "-1, the default: --init's, else 0"));
    a->Visit(AIA_FIELD(centre)
                 .In(Between(-1, 31))
                 .Doc("C: the C x C cells of the blocks' output around the "
                      "robot, read beside the pooled grid (odd; 0: none; "
                      "with --init the new inputs start at zero weight); -1, "
                      "the default: --init's, else 0"));
    a->Visit(AIA_FIELD(geodesic_length)
                 .In({-1.0, 1000.0, false, false})
                 .Doc("the reach channel's decay length L in metres (with "
                      "--init the weights are kept); -1, the default: "
                      "--init's, else 5"));
    a->Visit(AIA_FIELD(reach_detour)
                 .In({-1.0, 1000.0, false, false})
                 .Doc("with --reach-world 1: the reach channel dimmed by "
                      "each pixel's detour from the robot, exp(-detour / "
                      "this) in metres (0: off; with --init the weights are "
                      "kept); -1, the default: --init's, else 0"));
    a->Visit(AIA_FIELD(reach_broad)
                 .In({-1.0, 1000.0, false, false})
                 .Doc("with --reach-world 1: a last channel, the reach "
                      "channel again at this decay length in metres, without "
                      "the detour (0: off; with --init the new input starts "
                      "at zero weight); -1, the default: --init's, else 0"));
    a->Visit(AIA_FIELD(reach_second)
                 .In(Between(-1, 1))
                 .Doc("1: with --reach-world 1, a last channel, the reach "
                      "channel from each pixel's second target (same L and "
                      "detour; with --init the new input starts at zero "
                      "weight); -1, the default: --init's, else 0"));
    a->Visit(AIA_FIELD(neighbour_cap)
                 .In(Between(-1, 1000000))
                 .Doc("above 0: the neighbours channel holds at most this "
                      "many in a pixel (with --init the weights are kept); 0: "
                      "counts as they are; -1, the default: --init's, else 0"));
  }
  // lr_min <= lr; a length is -1 or above 0.
  void Validate(const FieldChecker& check) const {
    if (lr_min > lr) check.Fail(lr_min, "must be at most --lr");
    if (epochs == 0 && init.empty())
      check.Fail(epochs, "0 writes the --init model again: needs --init");
    if (geodesic_length != -1.0 && geodesic_length <= 0.0)
      check.Fail(geodesic_length, "must be -1 (the default) or above 0");
    if (reach_detour != -1.0 && reach_detour < 0.0)
      check.Fail(reach_detour, "must be -1 (the default), 0 or above");
    if (reach_broad != -1.0 && reach_broad < 0.0)
      check.Fail(reach_broad, "must be -1 (the default), 0 or above");
  }
};

struct EpochLog {
  int epoch = 0;    // 1-based
  double lr = 0.0;  // at the epoch's end
  double train_loss = 0.0, train_acc = 0.0;
  // NaN when no world was held out (--val-share 0, or too few worlds): an
  // empty field in the CSV log, "val: none" in the progress lines.
  double val_loss = 0.0, val_acc = 0.0;
  double val_acc_useful = 0.0;  // on the validation samples with useful work
                                // (NaN: none of them had useful work)
  long samples = 0;             // training samples seen in the epoch
  double seconds = 0.0;         // wall time of the epoch

  // The log's columns, declared once (core/csv.h): OUT.train.csv (CsvLine)
  // and the checkpoint's exact log (ExactLine) are both this list.
  template <typename C>
  void Columns(C* c) {
    c->Column("epoch", &epoch);
    c->Column("lr", &lr, CsvFormat::Significant(6));
    c->Column("train_loss", &train_loss, CsvFormat::Fixed(6));
    c->Column("train_acc", &train_acc, CsvFormat::Fixed(6));
    c->Column("val_loss", &val_loss, CsvFormat::Fixed(6, true));
    c->Column("val_acc", &val_acc, CsvFormat::Fixed(6, true));
    c->Column("val_acc_useful", &val_acc_useful, CsvFormat::Fixed(6, true));
    c->Column("samples", &samples);
    c->Column("seconds", &seconds, CsvFormat::Fixed(2));
  }
};

// "val loss L acc A (useful U)", or "val: none" without validation samples.
std::string ValidationText(const EpochLog& e);

// Where the checkpoint and the log go: OUT.ckpt and OUT minus ".pt" plus
// ".train.csv".
std::string CheckpointPath(const std::string& out);
std::string TrainLogPath(const std::string& out);

// Trains and writes the model after every epoch. Bad options or data are an
// InputError naming the flag.
std::vector<EpochLog> Train(const TrainOptions& options);

// The validation accuracy of a saved model on a dataset's held-out worlds
// (the same split as Train with `val_share` and `seed`), for comparisons;
// with `valid_moves`, loss and accuracy of the choice among the valid moves
// (TrainOptions::valid_moves).
struct ValidationResult {
  // NaN without held-out samples (acc_useful: without useful ones).
  double loss = std::numeric_limits<double>::quiet_NaN();
  double acc = std::numeric_limits<double>::quiet_NaN();
  double acc_useful = std::numeric_limits<double>::quiet_NaN();
  long samples = 0;
};
ValidationResult Validate(const std::string& model,
                          const std::vector<std::string>& data,
                          double val_share, std::uint64_t seed,
                          bool valid_moves = false);

// Samples per second of the network on random images of height x width:
// inference (evaluation mode, no gradients; the convolutions in bfloat16
// where `bf16`, learning/network.h) at `batch`, or training steps (forward,
// backward, Adam) at `batch`; the median of `repeats` timings of
// `iterations` calls each, after a warm-up.
double MeasureNetworkSpeed(const NetworkConfig& config, int height, int width,
                           int batch, bool train, int iterations, int repeats,
                           bool bf16 = false);

}  // namespace aia

#endif  // AIA_LEARNING_TRAINER_H_
