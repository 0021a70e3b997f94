// The processes of one job. Built with MPI (Debian's OpenMPI, optional) and
// started by mpirun, `aia eval` and `aia dataset` run as one rank each:
// eval hands instances out round-robin and rank 0 writes every row, dataset
// gives each rank its own shard. Without MPI, or started without mpirun, a
// job is one rank of one. No MPI type leaves ranks.cc.
#ifndef AIA_COMMANDS_RANKS_H_
#define AIA_COMMANDS_RANKS_H_

#include <functional>
#include <string>

namespace aia {

class Ranks {
 public:
  // Initializes MPI on first use when the process was started by mpirun (and
  // aia was built with MPI); finalized at exit.
  static Ranks& Get();

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool distributed() const { return size_ > 1; }
  // Whether this build can run under mpirun at all.
  static bool Built();

  // Rank 0 tells every rank whether to go on (after checks only it makes,
  // e.g. on the output folder); returns the verdict on every rank.
  bool AgreeFromRoot(bool go_on);
  // Returns on every rank once every rank has called it.
  void Barrier();

  // Ranks other than 0: one line of results to rank 0, then, once, the end
  // of this rank's work (`error` empty on success).
  void SendLine(const std::string& line);
  void SendDone(const std::string& error);
  // Rank 0: receives lines from every other rank until each has sent its
  // end, calling on_line for each (in arrival order); returns the first
  // error a rank reported, or "".
  std::string ReceiveAll(
      const std::function<void(const std::string&)>& on_line);

  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;

 private:
  Ranks();
  ~Ranks();
  int rank_ = 0;
  int size_ = 1;
  bool initialized_ = false;
};

}  // namespace aia

#endif  // AIA_COMMANDS_RANKS_H_
