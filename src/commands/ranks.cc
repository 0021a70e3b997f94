#include "aia/commands/ranks.h"

#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <thread>
#include <vector>

#ifdef AIA_WITH_MPI
#include <mpi.h>
#endif

namespace aia {
namespace {

#ifdef AIA_WITH_MPI
constexpr int kTagLine = 1;
constexpr int kTagDone = 2;

// Started by mpirun (OpenMPI or a PMI launcher such as Slurm's srun)?
bool UnderLauncher() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"})
    if (std::getenv(var) != nullptr) return true;
  return false;
}

void Check(int code, const char* what) {
  if (code != MPI_SUCCESS)
    throw std::runtime_error(std::string("MPI: ") + what + " failed");
}
#endif

}  // namespace

bool Ranks::Built() {
#ifdef AIA_WITH_MPI
  return true;
#else
  return false;
#endif
}

Ranks& Ranks::Get() {
  static Ranks ranks;
  return ranks;
}

Ranks::Ranks() {
#ifdef AIA_WITH_MPI
  if (!UnderLauncher()) return;
  // Serialized: in rank 0 one receiving thread, elsewhere the senders under
  // one lock, never two calls at once.
  int provided = 0;
  Check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided),
        "MPI_Init_thread");
  if (provided < MPI_THREAD_SERIALIZED)
    throw std::runtime_error(
        "MPI: this MPI library cannot be called from worker threads");
  initialized_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
#endif
}

Ranks::~Ranks() {
#ifdef AIA_WITH_MPI
  if (initialized_) MPI_Finalize();
#endif
}

bool Ranks::AgreeFromRoot(bool go_on) {
#ifdef AIA_WITH_MPI
  if (!initialized_) return go_on;
  int flag = go_on ? 1 : 0;
  Check(MPI_Bcast(&flag, 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Bcast");
  return flag != 0;
#else
  return go_on;
#endif
}

void Ranks::Barrier() {
#ifdef AIA_WITH_MPI
  if (initialized_) Check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
#endif
}

void Ranks::SendLine(const std::string& line) {
#ifdef AIA_WITH_MPI
  Check(MPI_Send(line.data(), static_cast<int>(line.size()), MPI_CHAR, 0,
                 kTagLine, MPI_COMM_WORLD),
        "MPI_Send");
#else
  (void)line;
#endif
}

void Ranks::SendDone(const std::string& error) {
#ifdef AIA_WITH_MPI
  Check(MPI_Send(error.data(), static_cast<int>(error.size()), MPI_CHAR, 0,
                 kTagDone, MPI_COMM_WORLD),
        "MPI_Send");
#else
  (void)error;
#endif
}

std::string Ranks::ReceiveAll(
    const std::function<void(const std::string&)>& on_line) {
  std::string first_error;
#ifdef AIA_WITH_MPI
  int open = size_ - 1;
  std::vector<char> buf;
  while (open > 0) {
    // Polled with a pause rather than a blocking probe, which spins a core
    // (OpenMPI busy-waits) that rank 0's own workers need.
    MPI_Status status;
    int pending = 0;
    Check(MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &pending,
                     &status),
          "MPI_Iprobe");
    if (!pending) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      continue;
    }
    int count = 0;
    MPI_Get_count(&status, MPI_CHAR, &count);
    buf.resize(static_cast<std::size_t>(count) + 1);
    Check(MPI_Recv(buf.data(), count, MPI_CHAR, status.MPI_SOURCE,
                   status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "MPI_Recv");
    const std::string text(buf.data(), static_cast<std::size_t>(count));
    if (status.MPI_TAG == kTagDone) {
      --open;
      if (!text.empty() && first_error.empty())
        first_error = "rank " + std::to_string(status.MPI_SOURCE) + ": " + text;
    } else {
      on_line(text);
    }
  }
#else
  (void)on_line;
#endif
  return first_error;
}

}  // namespace aia
