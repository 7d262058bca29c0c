// The main table of `cellray bench`: every scene x configuration x ray kind
// on identical ray sets. Per row: the structure (build time, bytes), the
// trace time (median, min and max of `repeat` timed runs after Prepare() and
// one untimed warm-up run; only Trace() is timed; by default the timed runs
// are taken in rounds over all of a scene's rows, BenchOptions::interleave),
// Havran's per-ray measures
// (a separate, untimed run on a tracer built with statistics), and the
// answers of the warm-up run checked against the fp64 reference
// (reference/check.h).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "host/bench/bench_options.h"
#include "host/bench/bench_row.h"
#include "host/bench/bench_scenes.h"

namespace cr::bench {

// Called after each row (progress on stderr); interleaved timing reports a
// scene's rows after its rounds, and says when the rounds begin (onNote).
using RowCallback = std::function<void(const Row&, std::size_t index, std::size_t total)>;
using NoteCallback = std::function<void(const std::string&)>;

std::vector<Row> RunRayBench(const BenchOptions& options, const std::vector<SceneRef>& scenes,
                             const std::vector<Combo>& combos, const RowCallback& onRow,
                             const NoteCallback& onNote = {});

// Traces `rays` once untimed (hits out), then `repeat` timed times.
// times: the rays' times (motion blur), or empty.
Timing TimeTrace(Tracer& tracer, const std::vector<RayRecord>& rays, const std::vector<float>& times, bool occlusion,
                 int repeat, std::vector<HitRecord>& hits);

}  // namespace cr::bench
