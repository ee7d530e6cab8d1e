// Generator programs: generation/cl_exec.py appends one kernel per pass (unit),
// compiled from a generation/lang.py Program. This file holds what they share.
#include "noise.h"

// Floor division and modulo by a positive constant (NumPy's // and %).
inline int vx_fdiv(int a, int n) { return (a - (a < 0 ? n - 1 : 0)) / n; }
inline int vx_fmod(int a, int n) { return a - vx_fdiv(a, n) * n; }
inline int vx_iabs(int a) { return a < 0 ? -a : a; }

// ---- generated passes ----
