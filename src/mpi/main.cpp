// freeflex_mpi: `freeflex run` for a design with a [sweep], its samples partitioned over
// MPI ranks (sample i on rank i mod size, each rank's share on --threads threads).
// Every rank computes the nominal studies (they are deterministic and cheap next to the
// sweep), flies its share, and all-gathers the samples; rank 0 writes the files, the
// same bytes as one process. Each rank keeps its own journal in DIR, so a killed job
// resumes with the same number of ranks.
//
//   mpirun -np 4 freeflex_mpi DESIGN --out DIR [--threads N] [--quiet]
#include <mpi.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "freeflex/app/run.hpp"
#include "freeflex/io/output.hpp"

namespace {

using namespace freeflex;

constexpr int kFixed = 10;  // index, ok, 6 metrics, wall time, spare

/// Replaces `samples`' entries of every other rank with theirs (the all-gather).
void gather(std::vector<SweepSample>& samples, int rank, int size, std::size_t parameters) {
  const long total = static_cast<long>(samples.size());
  const int F = kFixed + static_cast<int>(parameters);
  auto share = [&](int r) {
    std::vector<long> idx;
    for (long i = r; i < total; i += size) idx.push_back(i);
    return idx;
  };
  std::vector<double> mine;
  for (long i : share(rank)) {
    const SweepSample& s = samples[static_cast<std::size_t>(i)];
    const ResponseMetrics& m = s.metrics;
    const double row[kFixed] = {static_cast<double>(s.index), s.ok ? 1.0 : 0.0, m.residual_vibration_energy_J,
                                m.mean_vibration_energy_J, m.peak_tip_deflection_m, m.final_attitude_error_rad,
                                m.final_position_error_m, m.peak_command, s.wall_time_s, 0.0};
    mine.insert(mine.end(), row, row + kFixed);
    mine.insert(mine.end(), s.values.begin(), s.values.end());
  }
  std::vector<int> counts(static_cast<std::size_t>(size)), displs(static_cast<std::size_t>(size));
  int offset = 0;
  for (int r = 0; r < size; ++r) {
    counts[static_cast<std::size_t>(r)] = static_cast<int>(share(r).size()) * F;
    displs[static_cast<std::size_t>(r)] = offset;
    offset += counts[static_cast<std::size_t>(r)];
  }
  std::vector<double> all(static_cast<std::size_t>(offset));
  MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, all.data(), counts.data(), displs.data(),
                 MPI_DOUBLE, MPI_COMM_WORLD);
  for (int r = 0; r < size; ++r) {
    if (r == rank) continue;
    const double* p = all.data() + displs[static_cast<std::size_t>(r)];
    for (long i : share(r)) {
      SweepSample& s = samples[static_cast<std::size_t>(i)];
      s.index = static_cast<long>(p[0]);
      s.ok = p[1] != 0.0;
      s.metrics.residual_vibration_energy_J = p[2];
      s.metrics.mean_vibration_energy_J = p[3];
      s.metrics.peak_tip_deflection_m = p[4];
      s.metrics.final_attitude_error_rad = p[5];
      s.metrics.final_position_error_m = p[6];
      s.metrics.peak_command = p[7];
      s.wall_time_s = p[8];
      s.values.assign(p + kFixed, p + F);
      p += F;
    }
  }
}

int usage() {
  std::cerr << "usage: freeflex_mpi DESIGN --out DIR [--threads N] [--quiet]\n";
  return kExitBadInput;
}

int run(int argc, char** argv, int rank, int size) {
  std::string design_path, out;
  int threads = 0;
  bool quiet = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (a == "--quiet") quiet = true;
    else if (!a.empty() && a[0] != '-' && design_path.empty()) design_path = a;
    else return usage();
  }
  if (design_path.empty() || out.empty() || threads < 0) return usage();
  Design design;
  try {
    design = load_design(design_path);
  } catch (const DesignError& e) {
    if (rank == 0) std::cerr << e.what() << "\nfreeflex_mpi: problems in the design; nothing was run\n";
    return kExitBadInput;
  }
  if (!design.sweep) {
    if (rank == 0) std::cerr << "freeflex_mpi: the design has no [sweep]; run it with freeflex\n";
    return kExitBadInput;
  }
  RunOptions opt;
  opt.out_dir = rank == 0 ? out : "";
  opt.quiet = quiet || rank != 0;
  opt.log = &std::cout;
  opt.errors = &std::cerr;
  opt.sweep.threads = threads;
  opt.sweep.rank = rank;
  opt.sweep.ranks = size;
  const std::string journal = out + "/.freeflex-sweep-journal-" + std::to_string(rank) + "-of-" + std::to_string(size);
  opt.sweep.journal = journal;
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  const std::size_t parameters = design.sweep->parameters.size();
  opt.sweep.gather = [rank, size, parameters](std::vector<SweepSample>& s) { gather(s, rank, size, parameters); };
  const RunResult r = run_design(design, opt);
  MPI_Barrier(MPI_COMM_WORLD);  // rank 0 has committed the files: the journals are no longer needed
  std::filesystem::remove(journal, ec);
  if (!r.ok() && rank == 0) std::cerr << "freeflex_mpi: failed: " << r.message << '\n';
  return r.exit_code();
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int code = 0;
  try {
    code = run(argc, argv, rank, size);
  } catch (const std::exception& e) {
    std::cerr << "freeflex_mpi (rank " << rank << "): " << e.what() << '\n';
    code = kExitIoFailure;
  }
  MPI_Finalize();
  return code;
}
