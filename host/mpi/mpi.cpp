#include "host/mpi/mpi.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>

#include <fmt/format.h>

#include "host/core/error.h"

#ifdef CELLRAY_HAVE_MPI
#include <mpi.h>
#endif

namespace cr::mpi {

namespace {
int gRank = 0, gSize = 1;
bool gInit = false;
std::uint64_t gMessages = 0, gBytes = 0;

#ifdef CELLRAY_HAVE_MPI
// Started by a launcher: Open MPI's mpirun, MPICH's Hydra, or PMIx.
bool Launched()
{
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(v)) return true;
  return false;
}

void Check(int rc, const char* call)
{
  if (rc == MPI_SUCCESS) return;
  char msg[MPI_MAX_ERROR_STRING];
  int len = 0;
  MPI_Error_string(rc, msg, &len);
  throw RuntimeError(fmt::format("MPI: {} failed on {}: {}", call, RankName(), std::string(msg, std::size_t(len))));
}
#endif
}  // namespace

void Init(int* argc, char*** argv)
{
#ifdef CELLRAY_HAVE_MPI
  if (!Launched()) return;
  int provided = 0;
  if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
    std::fprintf(stderr, "cellray: MPI_Init_thread failed\n");
    std::exit(1);
  }
  gInit = true;
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &gRank);
  MPI_Comm_size(MPI_COMM_WORLD, &gSize);
#else
  (void)argc;
  (void)argv;
#endif
}

void Finalize()
{
#ifdef CELLRAY_HAVE_MPI
  if (gInit) MPI_Finalize();
  gInit = false;
#endif
}

int Rank() { return gRank; }
int Size() { return gSize; }

std::string RankName()
{
#ifdef CELLRAY_HAVE_MPI
  if (gInit) {
    char host[MPI_MAX_PROCESSOR_NAME];
    int len = 0;
    MPI_Get_processor_name(host, &len);
    return fmt::format("rank {} ({})", gRank, std::string(host, std::size_t(len)));
  }
#endif
  return "rank 0";
}

void Abort(const std::string& what, int code)
{
#ifdef CELLRAY_HAVE_MPI
  if (gInit && gSize > 1) {
    // A failure every rank meets alike (bad input) is reported once, by
    // rank 0: the others wait a moment for its abort to end them.
    if (gRank != 0) std::this_thread::sleep_for(std::chrono::milliseconds(300));
    std::fprintf(stderr, "cellray: %s%s\n", gRank == 0 ? "" : (RankName() + ": ").c_str(), what.c_str());
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, code);
  }
#endif
  std::fprintf(stderr, "cellray: %s\n", what.c_str());
  std::exit(code);
}

WorkCounter::WorkCounter(std::int64_t count) : count_(count)
{
#ifdef CELLRAY_HAVE_MPI
  if (!Distributed()) return;
  MPI_Win win = MPI_WIN_NULL;
  const MPI_Aint bytes = gRank == 0 ? MPI_Aint(sizeof(std::int64_t)) : 0;
  Check(MPI_Win_allocate(bytes, sizeof(std::int64_t), MPI_INFO_NULL, MPI_COMM_WORLD, &base_, &win), "MPI_Win_allocate");
  window_ = win;
  if (gRank == 0) {
    Check(MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, win), "MPI_Win_lock");
    *base_ = 0;
    Check(MPI_Win_unlock(0, win), "MPI_Win_unlock");
  }
  Check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
#endif
}

WorkCounter::~WorkCounter()
{
#ifdef CELLRAY_HAVE_MPI
  if (window_) {
    MPI_Win win = static_cast<MPI_Win>(window_);
    MPI_Win_free(&win);
  }
#endif
}

std::int64_t WorkCounter::Next()
{
#ifdef CELLRAY_HAVE_MPI
  if (window_) {
    MPI_Win win = static_cast<MPI_Win>(window_);
    const std::int64_t one = 1;
    std::int64_t got = 0;
    Check(MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, win), "MPI_Win_lock");
    Check(MPI_Fetch_and_op(&one, &got, MPI_INT64_T, 0, 0, MPI_SUM, win), "MPI_Fetch_and_op");
    Check(MPI_Win_unlock(0, win), "MPI_Win_unlock");
    ++gMessages;
    gBytes += sizeof(std::int64_t);
    return got < count_ ? got : -1;
  }
#endif
  return local_ < count_ ? local_++ : -1;
}

void Barrier()
{
#ifdef CELLRAY_HAVE_MPI
  if (Distributed()) Check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
#endif
}

std::vector<char> GatherBytes(const std::vector<char>& mine, std::vector<std::uint64_t>* sizes)
{
#ifdef CELLRAY_HAVE_MPI
  if (Distributed()) {
    const std::uint64_t n = mine.size();
    std::vector<std::uint64_t> all(gRank == 0 ? std::size_t(gSize) : 0);
    Check(MPI_Gather(&n, 1, MPI_UINT64_T, all.data(), 1, MPI_UINT64_T, 0, MPI_COMM_WORLD), "MPI_Gather");
    // MPI counts are int: a rank's part goes in pieces of at most 1 GiB.
    constexpr std::uint64_t kPiece = std::uint64_t(1) << 30;
    std::vector<char> out;
    if (gRank == 0) {
      std::uint64_t total = 0;
      for (std::uint64_t s : all) total += s;
      out.resize(total);
      std::copy(mine.begin(), mine.end(), out.begin());
      std::uint64_t at = n;
      for (int r = 1; r < gSize; ++r) {
        const std::uint64_t len = all[std::size_t(r)];
        for (std::uint64_t done = 0; done < len; done += kPiece)
          Check(MPI_Recv(out.data() + at + done, int(std::min(kPiece, len - done)), MPI_BYTE, r, 7, MPI_COMM_WORLD,
                         MPI_STATUS_IGNORE),
                "MPI_Recv");
        at += len;
      }
      if (sizes) *sizes = all;
    } else {
      for (std::uint64_t done = 0; done < n; done += kPiece) {
        const int len = int(std::min(kPiece, n - done));
        Check(MPI_Send(mine.data() + done, len, MPI_BYTE, 0, 7, MPI_COMM_WORLD), "MPI_Send");
        ++gMessages;
      }
      gBytes += n;
    }
    return out;
  }
#endif
  if (sizes) *sizes = {mine.size()};
  return mine;
}

std::vector<double> GatherDouble(double v)
{
#ifdef CELLRAY_HAVE_MPI
  if (Distributed()) {
    std::vector<double> all(gRank == 0 ? std::size_t(gSize) : 0);
    Check(MPI_Gather(&v, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, MPI_COMM_WORLD), "MPI_Gather");
    if (gRank != 0) ++gMessages, gBytes += sizeof(double);
    return all;
  }
#endif
  return {v};
}

void Broadcast(std::vector<char>& bytes)
{
#ifdef CELLRAY_HAVE_MPI
  if (Distributed()) {
    std::uint64_t n = bytes.size();
    Check(MPI_Bcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD), "MPI_Bcast");
    bytes.resize(n);
    constexpr std::uint64_t kPiece = std::uint64_t(1) << 30;
    for (std::uint64_t done = 0; done < n; done += kPiece)
      Check(MPI_Bcast(bytes.data() + done, int(std::min(kPiece, n - done)), MPI_BYTE, 0, MPI_COMM_WORLD), "MPI_Bcast");
  }
#else
  (void)bytes;
#endif
}

std::uint64_t SumAll(std::uint64_t v)
{
#ifdef CELLRAY_HAVE_MPI
  if (Distributed()) {
    std::uint64_t s = 0;
    Check(MPI_Allreduce(&v, &s, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
    return s;
  }
#endif
  return v;
}

void SumAll(std::uint64_t* v, int n)
{
#ifdef CELLRAY_HAVE_MPI
  if (Distributed())
    Check(MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
#else
  (void)v;
  (void)n;
#endif
}

void Exchange(const std::vector<std::vector<char>>& out, std::vector<std::vector<char>>& in)
{
  in.resize(out.size());
#ifdef CELLRAY_HAVE_MPI
  if (Distributed()) {
    const std::size_t n = std::size_t(gSize);
    static thread_local std::vector<char> send, recv;
    std::vector<int> sendCount(n), recvCount(n), sendAt(n), recvAt(n);
    std::size_t total = 0;
    for (std::size_t r = 0; r < n; ++r) total += out[r].size();
    if (total > (std::size_t(1) << 31) - 1)
      throw RuntimeError(fmt::format("MPI: one exchange of {} bytes is over 2 GiB", total));
    send.resize(total);
    total = 0;
    for (std::size_t r = 0; r < n; ++r) {
      sendAt[r] = int(total);
      sendCount[r] = int(out[r].size());
      if (!out[r].empty()) std::memcpy(send.data() + total, out[r].data(), out[r].size());
      total += out[r].size();
      if (!out[r].empty() && int(r) != gRank) ++gMessages, gBytes += out[r].size();
    }
    Check(MPI_Alltoall(sendCount.data(), 1, MPI_INT, recvCount.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Alltoall");
    total = 0;
    for (std::size_t r = 0; r < n; ++r) recvAt[r] = int(total), total += std::size_t(recvCount[r]);
    if (total > (std::size_t(1) << 31) - 1)
      throw RuntimeError(fmt::format("MPI: one exchange of {} bytes is over 2 GiB", total));
    recv.resize(total);
    Check(MPI_Alltoallv(send.data(), sendCount.data(), sendAt.data(), MPI_BYTE, recv.data(), recvCount.data(),
                        recvAt.data(), MPI_BYTE, MPI_COMM_WORLD),
          "MPI_Alltoallv");
    for (std::size_t r = 0; r < n; ++r) in[r].assign(recv.begin() + recvAt[r], recv.begin() + recvAt[r] + recvCount[r]);
    return;
  }
#endif
  for (std::size_t r = 0; r < out.size(); ++r) in[r] = out[r];
}

std::uint64_t MessagesSent() { return gMessages; }
std::uint64_t BytesSent() { return gBytes; }

}  // namespace cr::mpi
