#include "slam/solver_logging.hpp"

#include <glog/logging.h>

namespace builtscene::slam {

void init_solver_logging(const char* program, int verbosity) {
  static bool done = false;
  FLAGS_logtostderr = true;
  FLAGS_minloglevel = verbosity >= 2 ? google::GLOG_INFO : google::GLOG_ERROR;
  if (!done) google::InitGoogleLogging(program);
  done = true;
}

}  // namespace builtscene::slam
