#pragma once
// A study on MPI ranks (issue 12): `mpirun -np N roverplan study run ...`. Rank 0 reads the spec,
// broadcasts it, owns the study database (the only writer) and hands out chunks of run indices on
// demand: a rank asks for work, gets a chunk and returns its rows with its next request, so ranks
// that draw slow runs (team missions vary 10× in cost) simply ask less often. Chunks shrink as the
// study ends (guided: remaining / (4 · threads everywhere), at most 256), which keeps the tail
// short. Rank 0 also runs its own share on worker threads while its main thread serves requests
// and commits; MPI is called from the main threads only (MPI_THREAD_FUNNELED). The rows are the
// same as in threads mode: each is a pure function of (spec, run index).
#include <functional>
#include <iosfwd>
#include <string>

#include <nlohmann/json.hpp>

#include "server/studies/study_runner.hpp"

namespace rover::studies {

// Whether this roverplan was built with MPI (CMake found it).
bool mpiBuilt();
// The rank count an MPI launcher gave this process (Open MPI's OMPI_COMM_WORLD_SIZE, PMI_SIZE,
// PMIX / Slurm's SLURM_NTASKS under srun), or 0 when it was not launched as MPI ranks.
int mpiLaunchSize();
// Processes of this job on this host (OMPI_COMM_WORLD_LOCAL_SIZE), for the default thread count.
int mpiLocalSize();

// Collective: every rank calls it. `specOnRoot` runs on rank 0 only (its errors are rethrown
// there; the other ranks return 2 without a word). Rank 0 writes `dbPath`, prints progress to
// `out` and returns 0 with `report` filled; worker ranks return 0 when the study is done. Any
// rank's failure aborts the job (MPI_Abort) after printing one line. Without MPI: throws.
int runStudyMpi(const std::function<nlohmann::json()>& specOnRoot, const std::string& dbPath,
                const RunOptions& options, const ProgressFn& progress, RunReport& report, bool& isRoot);

}  // namespace rover::studies
