"""The assembled chain: the paper's matrices and the compiled O(n) kernels."""
