"""The mechanics layer, between the vocabulary (``rodval.core``) and the integrators
(``rodval.solvers``): physics every model shares and no single model owns: the rigid lock
impulse, the lock window, the symmetric eigenproblems, the modal analysis's computations, the
momentum of a chain about its root."""
