// Runs straight from crossings (voxd/voxelize/runs.h). A chunk of z layers is
// scan-converted into a list of (row, crossing) pairs and, with a surface,
// (row, span) triples; a counting sort by row puts each row's together, a
// short sort orders them along the row, and the parity of the crossings
// gives the solid's runs, merged with the surface's spans. Work and memory
// follow the crossings and spans, about N^2 at N^3 voxels, where the dense
// path clears, toggles, prefix-XORs and re-scans N^3 / 8 bytes.
#include "voxd/voxelize/runs.h"

#include <algorithm>
#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "encode/ordered_pipeline.h"
#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxd/uncleared_vector.h"
#include "voxelize/layer_range.h"
#include "voxelize/parity_voxelizer.h"
#include "voxelize/surface_voxelizer.h"

namespace voxd {
namespace {

using detail::ParityVoxelizer;
using detail::SurfaceVoxelizer;

// Rows hold a handful of crossings (2 or 4 through a torus): insertion sort
// beats std::sort's set-up there; long rows (a surface grazing a row) fall
// back to it.
template <class T, class Less>
void sort_short(T* first, T* last, Less less) {
  if (last - first > 24) {
    std::sort(first, last, less);
    return;
  }
  for (T* i = first + 1; i < last; ++i) {
    T v = *i;
    T* j = i;
    for (; j > first && less(v, *(j - 1)); --j) *j = *(j - 1);
    *j = v;
  }
}

// Joins runs that arrive in increasing order of their begin into maximal
// runs of the row: overlapping and touching runs merge, empty ones vanish.
class RowRunJoiner {
 public:
  explicit RowRunJoiner(RunSlab& slab) : slab_(slab) {}
  void add(std::uint32_t begin, std::uint32_t end) {
    if (begin >= end) return;
    if (open_ && begin <= end_) {
      end_ = std::max(end_, end);
      return;
    }
    if (open_) slab_.add_run(begin_, end_);
    open_ = true;
    begin_ = begin;
    end_ = end;
  }
  void end_row() {
    if (open_) slab_.add_run(begin_, end_);
    open_ = false;
    slab_.end_row();
  }

 private:
  RunSlab& slab_;
  bool open_ = false;
  std::uint32_t begin_ = 0, end_ = 0;
};

// One chunk's scratch and result, reused for the next chunk in its slot.
struct ChunkRuns {
  RunSlab slab;
  std::vector<ParityVoxelizer::RowCrossing> crossings;
  std::vector<SurfaceVoxelizer::RowSpan> spans;
  std::vector<std::uint32_t> crossing_start, span_start;  // per row, counting sort
  std::vector<std::uint32_t> xs;                           // crossings by row
  std::vector<std::pair<std::uint32_t, std::uint32_t>> row_spans;  // spans by row

  // Gives the memory back, its pages by this thread (one of the threads
  // sharing out the slots): freed in turn, the allocator would trim its
  // heap of them all at the last free, on one thread.
  void free_memory() {
    slab.free_on_every_thread(1);
    free_on_every_thread(crossings, 1);
    free_on_every_thread(spans, 1);
    free_on_every_thread(crossing_start, 1);
    free_on_every_thread(span_start, 1);
    free_on_every_thread(xs, 1);
    free_on_every_thread(row_spans, 1);
  }
};

// Counting sort of `items` by their row: start[r] .. start[r + 1] index the
// row's values in `out`.
template <class Item, class Value, class Get>
void sort_by_row(const std::vector<Item>& items, std::int64_t rows, std::vector<std::uint32_t>& start,
                 std::vector<Value>& out, Get get) {
  start.assign(static_cast<std::size_t>(rows) + 1, 0);
  for (const Item& it : items) ++start[it.row + 1];
  for (std::size_t r = 1; r < start.size(); ++r) start[r] += start[r - 1];
  out.resize(items.size());
  // Places with a cursor per row taken from start (shifted back afterwards).
  for (const Item& it : items) out[start[it.row]++] = get(it);
  for (std::size_t r = start.size() - 1; r > 0; --r) start[r] = start[r - 1];
  start[0] = 0;
}

void make_chunk_runs(const ParityVoxelizer* parity, const SurfaceVoxelizer* surface, const Grid& grid,
                     std::int64_t chunk, std::int64_t k0, std::int64_t layers, ChunkRuns& c) {
  const std::int64_t rows = layers * grid.dims.y;
  const auto nx = static_cast<std::uint32_t>(grid.dims.x);
  c.slab.reset(slab_grid(grid, k0, layers));
  c.crossings.clear();
  c.spans.clear();
  if (parity) {
    parity->chunk_crossings(chunk, c.crossings);
    sort_by_row(c.crossings, rows, c.crossing_start, c.xs, [](const auto& x) { return x.x; });
  }
  if (surface) {
    surface->chunk_spans(chunk, c.spans);
    sort_by_row(c.spans, rows, c.span_start, c.row_spans, [](const auto& s) { return std::pair(s.begin, s.end); });
  }
  RowRunJoiner joiner(c.slab);
  const auto by_begin = [](const auto& a, const auto& b) { return a.first < b.first; };
  for (std::int64_t r = 0; r < rows; ++r) {
    std::uint32_t* x = nullptr;
    std::uint32_t* x_end = nullptr;
    if (parity) {
      x = c.xs.data() + c.crossing_start[static_cast<std::size_t>(r)];
      x_end = c.xs.data() + c.crossing_start[static_cast<std::size_t>(r) + 1];
      sort_short(x, x_end, std::less<>());
    }
    std::pair<std::uint32_t, std::uint32_t>* s = nullptr;
    std::pair<std::uint32_t, std::uint32_t>* s_end = nullptr;
    if (surface) {
      s = c.row_spans.data() + c.span_start[static_cast<std::size_t>(r)];
      s_end = c.row_spans.data() + c.span_start[static_cast<std::size_t>(r) + 1];
      sort_short(s, s_end, by_begin);
    }
    // Crossings pair up into the solid's runs: [x0, x1), [x2, x3), ...; an
    // odd last one runs to the row's end (the grid cuts the part). Equal
    // crossings make empty runs, which the joiner drops; the surface's spans
    // go in between, by their begin.
    while (x != x_end) {
      const std::uint32_t b = x[0], e = x + 1 != x_end ? x[1] : nx;
      x += x + 1 != x_end ? 2 : 1;
      for (; s != s_end && s->first < b; ++s) joiner.add(s->first, s->second);
      joiner.add(b, e);
    }
    for (; s != s_end; ++s) joiner.add(s->first, s->second);
    joiner.end_row();
  }
}

}  // namespace

bool can_make_runs(const VoxelizeOptions& options) { return can_stream(options); }

void voxelize_runs(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options, const RunSlabConsumer& consume,
                   JobControl* control, LayerRange range, const RunSlabPreparer& prepare) {
  if (!can_make_runs(options))
    throw Error(ErrorCode::invalid_argument, std::string("the ") + to_string(options.inside) +
                                                 " inside test needs the whole grid; only parity makes runs row by row");
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  const std::int64_t requested = range.end < 0 ? grid.dims.z - range.begin : range.end - range.begin;
  // Enough chunks to balance the threads, few enough that triangles rarely
  // straddle two (each straddling one is scan-converted once per chunk).
  const detail::LayerChunks chunks =
      detail::layer_chunks(grid, range, std::clamp<std::int64_t>(requested / (8 * threads), 1, 16));
  if (grid.voxel_count() == 0) return;

  std::optional<ParityVoxelizer> parity;
  std::optional<SurfaceVoxelizer> surface;
  if (options.mode != VoxelMode::surface) parity.emplace(mesh, grid, 0, threads, chunks.per_chunk);
  if (options.mode != VoxelMode::solid) surface.emplace(mesh, grid, threads, chunks.per_chunk);

  const std::int64_t c0 = chunks.first_chunk(), count = chunks.end_chunk() - c0;
  const auto first_layer = [&](std::int64_t i) { return std::max(chunks.first, (c0 + i) * chunks.per_chunk); };
  const auto layer_count = [&](std::int64_t i) {
    return std::min(chunks.end, (c0 + i + 1) * chunks.per_chunk) - first_layer(i);
  };
  // Four slots a thread: two chunks in flight per thread keep every thread
  // busy while the consumer takes the oldest, and the other two let the
  // rest go on while a thread is descheduled mid-chunk (a busy machine; with
  // two a thread, 16 threads on 2 cores took 0.83 s for the torus at 8192^3
  // against 0.76 s, though 16 cores would not wait: the schedule
  // simulation, which counts slots, finds both at the pipeline's ideal).
  // Only the consumer is serial: whatever of its
  // work `prepare` does runs on the threads that make the chunks (at 16
  // threads, encoding each chunk's RLE on the consumer's thread alone
  // bounded the whole run, docs/benchmarks.md).
  std::vector<ChunkRuns> slots(static_cast<std::size_t>(std::min<std::int64_t>(count, 4 * threads)));
  encode::run_ordered_pipeline(
      count, threads, slots.size(),
      [&](std::int64_t i, std::size_t slot) {
        if (control) control->check_cancelled();
        make_chunk_runs(parity ? &*parity : nullptr, surface ? &*surface : nullptr, grid, c0 + i, first_layer(i),
                        layer_count(i), slots[slot]);
        if (prepare) prepare(first_layer(i), slots[slot].slab);
      },
      [&](std::int64_t i, std::size_t slot) {
        consume(first_layer(i), slots[slot].slab);
        if (control)
          control->set_progress(static_cast<double>(first_layer(i) + layer_count(i) - chunks.first) /
                                static_cast<double>(chunks.end - chunks.first));
      });
  // The slots' memory given back on every thread: on 16 threads they are 64
  // chunks' crossings and runs, and unmapping them on the calling thread
  // took 20 ms of the 8192^3 solid's 95 ms there (the schedule simulation).
  // Each slot's pages are dropped by the thread that frees it: freed alone,
  // blocks from one heap were given back together, by the last free.
  parallel_for(0, static_cast<std::int64_t>(slots.size()), 1, threads, [&](std::int64_t a, std::int64_t b) {
    for (std::int64_t i = a; i < b; ++i) slots[static_cast<std::size_t>(i)].free_memory();
  });
}

}  // namespace voxd
