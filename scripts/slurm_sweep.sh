#!/bin/bash
# A [sweep] on a Slurm cluster: samples spread over MPI ranks (sample i on rank i mod N),
# each rank's share over the cores Slurm gives it. The results are the same bytes as
# `freeflex run DESIGN` on one machine. If the job is killed (time limit, preemption),
# submit it again with the same number of tasks: every rank resumes from its journal in
# the output directory and flies only the samples it had not finished.
#
#   sbatch scripts/slurm_sweep.sh designs/sweep_slew.toml results/sweep_slew
#
#SBATCH --job-name=freeflex-sweep
#SBATCH --nodes=4
#SBATCH --ntasks-per-node=1
#SBATCH --cpus-per-task=32
#SBATCH --time=01:00:00
#SBATCH --output=freeflex-sweep-%j.log
set -euo pipefail
design=${1:?usage: sbatch slurm_sweep.sh DESIGN OUT_DIR}
out=${2:?usage: sbatch slurm_sweep.sh DESIGN OUT_DIR}
# one rank per node, one thread per core given to the task; the output directory must be
# on a file system every node sees (rank 0 writes the results, every rank its journal)
srun --cpus-per-task="$SLURM_CPUS_PER_TASK" freeflex_mpi "$design" --out "$out" --threads "$SLURM_CPUS_PER_TASK"
