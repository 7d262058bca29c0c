// Octree builder: placeholder until the accel issue lands.
#include "accel/accel.h"
#include "core/error.h"

namespace cr {
OctreeData BuildOctree(const Scene&, const AccelParams&, AccelInfo&)
{
  throw InputError("--accel octree: not implemented yet");
}
}  // namespace cr
