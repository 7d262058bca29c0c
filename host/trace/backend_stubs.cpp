// Backends that have not landed yet.
#include "core/error.h"
#include "trace/tracer.h"

namespace cr {
std::unique_ptr<Tracer> CreateOpenCLTracer(const Scene&, const TraceConfig&)
{
  throw RuntimeError("--backend opencl: not implemented yet");
}
}  // namespace cr
