// Uniform grid builder: placeholder until the accel issue lands.
#include "accel/accel.h"
#include "core/error.h"

namespace cr {
GridData BuildGrid(const Scene&, const AccelParams&, AccelInfo&) { throw InputError("--accel grid: not implemented yet"); }
}  // namespace cr
