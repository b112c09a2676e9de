#pragma once
// Ceres reports through glog. Without this, every run printed "WARNING: Logging before
// InitGoogleLogging()" and, on bundle adjustment's rank-deficient steps (Levenberg-Marquardt
// then raises its damping and goes on: nothing for a user to act on), "Linear solver failure
// ... dense Cholesky" lines on stderr. They are shown with -v (verbosity >= 2) only.
namespace builtscene::slam {

void init_solver_logging(const char* program, int verbosity);

}  // namespace builtscene::slam
