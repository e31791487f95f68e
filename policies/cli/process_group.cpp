#include "policies/cli/process_group.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdlib>

#define OMPI_SKIP_MPICXX 1  // the C interface only
#include <mpi.h>

namespace pbppo::cli {

bool ProcessGroup::UnderMpirun() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMIX_RANK") != nullptr;
}

ProcessGroup::ProcessGroup() {
  if (!UnderMpirun()) return;
  MPI_Init(nullptr, nullptr);
  mpi_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

ProcessGroup::~ProcessGroup() {
  if (mpi_) MPI_Finalize();
}

namespace {
// MPI counts are ints: larger messages go in pieces of this many bytes.
constexpr std::size_t kPiece = std::size_t{1} << 30;
}  // namespace

void ProcessGroup::Broadcast(void* data, std::size_t bytes, int root) const {
  if (!mpi_) return;
  auto* p = static_cast<char*>(data);
  for (std::size_t done = 0; done < bytes; done += kPiece) {
    const std::size_t n = std::min(kPiece, bytes - done);
    MPI_Bcast(p + done, static_cast<int>(n), MPI_BYTE, root, MPI_COMM_WORLD);
  }
}

std::vector<std::vector<char>> ProcessGroup::AllGather(std::span<const char> mine) const {
  if (!mpi_) return {std::vector<char>(mine.begin(), mine.end())};
  const std::uint64_t len = mine.size();
  std::vector<std::uint64_t> lens(static_cast<std::size_t>(size_));
  MPI_Allgather(&len, 1, MPI_UINT64_T, lens.data(), 1, MPI_UINT64_T, MPI_COMM_WORLD);
  std::vector<std::vector<char>> all(static_cast<std::size_t>(size_));
  for (int r = 0; r < size_; ++r) {
    auto& v = all[static_cast<std::size_t>(r)];
    if (r == rank_) {
      v.assign(mine.begin(), mine.end());
    } else {
      v.resize(static_cast<std::size_t>(lens[static_cast<std::size_t>(r)]));
    }
    Broadcast(v.data(), v.size(), r);
  }
  return all;
}

void ProcessGroup::Abort(int rc) const {
  if (mpi_) MPI_Abort(MPI_COMM_WORLD, rc);
  std::exit(rc);
}

void ProcessGroup::Broadcast(std::vector<long>& v) const {
  if (!mpi_) return;
  long n = static_cast<long>(v.size());
  MPI_Bcast(&n, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  v.resize(static_cast<std::size_t>(n));
  MPI_Bcast(v.data(), static_cast<int>(n), MPI_LONG, 0, MPI_COMM_WORLD);
}

std::vector<std::string> ProcessGroup::Gather(const std::string& mine) const {
  if (!mpi_) return {mine};
  int len = static_cast<int>(mine.size());
  std::vector<int> lens(static_cast<std::size_t>(size_)), offsets(static_cast<std::size_t>(size_));
  MPI_Gather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  int total = 0;
  for (int r = 0; r < size_; ++r) {
    offsets[static_cast<std::size_t>(r)] = total;
    total += lens[static_cast<std::size_t>(r)];
  }
  std::string all(rank_ == 0 ? static_cast<std::size_t>(total) : 0, '\0');
  MPI_Gatherv(mine.data(), len, MPI_CHAR, all.data(), lens.data(), offsets.data(), MPI_CHAR, 0, MPI_COMM_WORLD);
  if (rank_ != 0) return {};
  std::vector<std::string> out;
  for (int r = 0; r < size_; ++r)
    out.push_back(all.substr(static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]),
                             static_cast<std::size_t>(lens[static_cast<std::size_t>(r)])));
  return out;
}

}  // namespace pbppo::cli
