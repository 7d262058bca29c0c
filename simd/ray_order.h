// Packet formation: orders in which to hand rays to the packet kernels so
// that the N rays of a packet take similar paths through the BVH. The
// kernels read rays through the order and scatter each hit back to its
// ray's own index, so an order changes speed only, never answers.
#pragma once

#include <span>
#include <cstdint>
#include <vector>

#include "kernels/types.h"

namespace cr::simd {

// Width of the image a ray set of primary rays was made for: every ray has
// the same origin and the directions step by one constant vector along
// rows of W rays (host/scene/camera.cpp PrimaryRay, row-major). 0 when the
// set does not look like that.
int DetectImageWidth(std::span<const RayRecord> rays);

// Positions of the rays of a W-wide row-major image in tiles of tileW x tileH
// pixels (tileW * tileH = the packet width), tiles row by row: a packet
// covers a compact tile instead of a row segment.
std::vector<std::uint32_t> TileOrder(std::size_t nRays, int imageWidth, int tileW, int tileH);

// Ray indices grouped by direction class (the signs of the three direction
// components and the dominant axis: 24 classes), in input order inside each
// class: a stable counting sort. Some packet traversals run once per class
// of direction signs among their lanes (simd_kernels.h PacketOrder), so on
// incoherent sets (shadow rays towards several lights, diffuse and random
// rays) this turns passes of one or two lanes into passes of full packets.
std::vector<std::uint32_t> DirectionClassOrder(std::span<const RayRecord> rays);

}  // namespace cr::simd
