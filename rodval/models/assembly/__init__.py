"""The assembled chain system: the paper's matrices, the compiled O(n) kernels, the system and its
energies."""
