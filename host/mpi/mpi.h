// Running across processes and machines with MPI (Open MPI; optional: built
// when CMake finds it, CELLRAY_HAVE_MPI). `mpirun -np N cellray render|trace
// ...` splits the work among N ranks; without mpirun, or in a build without
// MPI, the program is one rank and behaves exactly as it does alone (MPI is
// not even initialised).
//
// Distribution of a render (docs/DISTRIBUTED.md):
//  - tiles (default): the scene on every rank; the image cut into tiles of a
//    few whole rows, handed out dynamically by one atomic counter on rank 0
//    (MPI_Fetch_and_op on a one-sided window, so that rank 0 renders too and
//    no rank serves requests); the frame assembled on rank 0;
//  - bands: the hypercube paper's static horizontal bands, one per rank, in
//    ring order.
// A pixel's value depends only on its own samples, so the assembled image
// is bit-identical to one process's.
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>
#include <string>
#include <vector>

namespace cr::mpi {

// MPI_Init_thread when the process was started by mpirun (Open MPI's, MPICH's
// or a PMIx launcher's environment); otherwise nothing. Finalize at exit.
void Init(int* argc, char*** argv);
void Finalize();
// This process's rank and the number of ranks (0 and 1 without MPI).
int Rank();
int Size();
inline bool Distributed() { return Size() > 1; }
// A name for messages: "rank 3 (host)".
std::string RankName();

// Ends the whole job: prints `cellray: rank R: what` and calls MPI_Abort
// with `code` (exit code 2 for bad input, 1 for a runtime failure). Without
// MPI, returns (the caller exits normally).
[[noreturn]] void Abort(const std::string& what, int code);

// Dynamic work: every rank calls Next() until it returns -1; each index in
// [0, count) goes to exactly one rank. Collective construction and
// destruction.
class WorkCounter {
 public:
  explicit WorkCounter(std::int64_t count);
  ~WorkCounter();
  WorkCounter(const WorkCounter&) = delete;
  WorkCounter& operator=(const WorkCounter&) = delete;
  std::int64_t Next();

 private:
  std::int64_t count_ = 0;
  std::int64_t local_ = 0;  // one process: the next index
  void* window_ = nullptr;  // MPI_Win (opaque here)
  std::int64_t* base_ = nullptr;
};

// Collectives over MPI_COMM_WORLD (no-ops for one process).
void Barrier();
// Every rank's bytes to rank 0, concatenated in rank order there (others get
// an empty vector); also the per-rank sizes on rank 0.
std::vector<char> GatherBytes(const std::vector<char>& mine, std::vector<std::uint64_t>* sizes = nullptr);
// A plain struct from every rank, on rank 0 in rank order (others: empty).
template <class T>
std::vector<T> GatherAll(const T& mine)
{
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<char> bytes(sizeof(T));
  std::memcpy(bytes.data(), &mine, sizeof(T));
  const std::vector<char> all = GatherBytes(bytes);
  std::vector<T> out(all.size() / sizeof(T));
  if (!out.empty()) std::memcpy(out.data(), all.data(), out.size() * sizeof(T));
  return out;
}
// The same double from every rank, on rank 0 (others: empty).
std::vector<double> GatherDouble(double v);
// Rank 0's bytes to every rank.
void Broadcast(std::vector<char>& bytes);
// Sum over ranks, result on every rank.
std::uint64_t SumAll(std::uint64_t v);
// Element-wise sums over ranks of n counters, in place on every rank.
void SumAll(std::uint64_t* v, int n);
// Personalised all-to-all: out[r] goes to rank r (out has Size() entries;
// an empty one sends nothing); in[r] gets what rank r sent here. The
// buffers are reused from call to call (no fresh pages per round). One
// process: in = out.
void Exchange(const std::vector<std::vector<char>>& out, std::vector<std::vector<char>>& in);
// Messages and bytes this rank has sent through these collectives.
std::uint64_t MessagesSent();
std::uint64_t BytesSent();

}  // namespace cr::mpi
