// The hash grid over an iteration's light vertices for photon merging: `src/accel/hash_grid.rs` again,
// with the same names. Cells of side 2r hashed into a power of two of buckets (at least as many
// as vertices); the vertices sorted by bucket with a counting sort in dispatches: grid_setup
// (the bucket count from the vertex count), grid_count (an atomic count per bucket),
// grid_scan_blocks, grid_scan_sums and grid_scan_add (the prefix sum), grid_scatter (each vertex
// to its bucket's next slot, by an atomic cursor), grid_sort (each bucket in the order of its
// vertices' light subpath and length, which is the CPU's vertex order), then grid_records (what
// a merge reads of each entry's vertex, in entry order). So the buckets list the same vertices in
// the same order on both backends, and merges sum in the same order.

// The grid's constants (`GridParams`): the host writes min, inv_cell and radius2, grid_setup
// the mask and the count.
struct GridParams {
    min: vec3<f32>,
    inv_cell: f32,
    mask: u32,
    count: u32,
    radius2: f32,
    pad: u32,
}

@group(1) @binding(3) var<storage, read_write> grid_params: GridParams;
// Bucket b's entries are grid_entries[grid_starts[b] .. grid_starts[b + 1]].
@group(1) @binding(4) var<storage, read_write> grid_starts: array<atomic<u32>>;
// (position, vertex index bits), by bucket.
@group(1) @binding(5) var<storage, read_write> grid_entries: array<vec4<f32>>;
// Each bucket's next free slot during the scatter.
@group(1) @binding(6) var<storage, read_write> grid_cursor: array<atomic<u32>>;
// What a merge reads of entry e's vertex, at photon_records[e] (grid_records).
@group(1) @binding(7) var<storage, read_write> photon_records: array<PhotonRecord>;

// Cell coordinates are clamped to +-2^30 before hashing (`CELL_LIMIT`).
const CELL_LIMIT: f32 = 1073741824.0;
// The slack, in cell units, by which a query takes a neighbouring cell its ball nearly reaches.
const QUERY_MARGIN: f32 = 0.0009765625;

// The hash of a cell: three large primes, wrapping u32 arithmetic (`hash_cell`).
fn hash_cell(c: vec3<i32>) -> u32 {
    let u = bitcast<vec3<u32>>(c);
    return (u.x * 73856093u) ^ (u.y * 19349663u) ^ (u.z * 83492791u);
}

// The point's position in cell units.
fn cell_units(p: vec3<f32>) -> vec3<f32> {
    return clamp((p - grid_params.min) * grid_params.inv_cell, vec3<f32>(-CELL_LIMIT), vec3<f32>(CELL_LIMIT));
}

// The bucket of the cell holding p.
fn grid_bucket(p: vec3<f32>) -> u32 {
    return hash_cell(vec3<i32>(floor(cell_units(p)))) & grid_params.mask;
}

// The buckets of the cells that hold every point within share * r of p (share <= 1), each once:
// the first n (hash_grid.rs: GridParams::query_buckets).
struct QueryBuckets {
    b: array<u32, 8>,
    n: u32,
}

fn query_buckets(p: vec3<f32>, share: f32) -> QueryBuckets {
    let u = cell_units(p);
    let cf = floor(u);
    let f = u - cf;
    let c = vec3<i32>(cf);
    // Per axis, the neighbour on the side of the nearer face, if the ball reaches it.
    let reach = 0.5 * share + QUERY_MARGIN;
    let near = select(vec3<i32>(1), vec3<i32>(-1), f < vec3<f32>(0.5));
    let step = select(near, vec3<i32>(0), min(f, 1.0 - f) >= vec3<f32>(reach));
    var out: QueryBuckets;
    out.n = 0u;
    for (var k = 0u; k < 8u; k++) {
        let offset = vec3<i32>(vec3<u32>(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u));
        let b = hash_cell(c + offset * step) & grid_params.mask;
        var seen = false;
        for (var j = 0u; j < out.n; j++) {
            seen = seen || out.b[j] == b;
        }
        if !seen {
            out.b[out.n] = b;
            out.n += 1u;
        }
    }
    return out;
}

// One invocation: the vertex count of the iteration (what fits in the pool) and the buckets,
// the next power of two at least as large.
@compute @workgroup_size(1, 1, 1)
fn grid_setup() {
    let count = min(atomicLoad(&tallies[vertex_counter()]), frame.vertex_capacity);
    grid_params.count = count;
    let n = max(count, 1u);
    grid_params.mask = select((2u << (31u - countLeadingZeros(n - 1u))) - 1u, 0u, n == 1u);
}

// One invocation per vertex (from frame.path_origin): count it in its bucket (grid_starts[b + 1], so that the prefix
// sum leaves each bucket's start at grid_starts[b]).
@compute @workgroup_size(64, 1, 1)
fn grid_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = frame.path_origin + gid.x;
    if i >= grid_params.count {
        return;
    }
    atomicAdd(&grid_starts[grid_bucket(light_vertices[i].p) + 1u], 1u);
}

// The inclusive prefix sum over grid_starts[1 ..= buckets] in three dispatches, so that it
// spreads over the whole GPU (one workgroup alone took 59 % of an sppm iteration on an H100 at
// 512x512, docs/journal/2026-11-26_h100.md): grid_scan_blocks scans blocks of SCAN_BLOCK counts in place, one
// workgroup each, and leaves each block's total in grid_cursor (free until the scatter);
// grid_scan_sums scans those totals in one workgroup; grid_scan_add adds to each block the
// totals of the blocks before it. Integer sums, so the starts are the CPU's exactly.
const SCAN_THREADS: u32 = 256u;
const SCAN_PER_THREAD: u32 = 4u;
const SCAN_BLOCK: u32 = SCAN_THREADS * SCAN_PER_THREAD;
var<workgroup> scan_partial: array<u32, 256>;

// The inclusive scan of the workgroup's per-invocation totals in scan_partial (Hillis-Steele);
// returns the sum of the totals before this invocation's.
fn scan_workgroup(lid: u32, total: u32) -> u32 {
    scan_partial[lid] = total;
    workgroupBarrier();
    for (var stride = 1u; stride < SCAN_THREADS; stride <<= 1u) {
        var add = 0u;
        if lid >= stride {
            add = scan_partial[lid - stride];
        }
        workgroupBarrier();
        scan_partial[lid] += add;
        workgroupBarrier();
    }
    return scan_partial[lid] - total;
}

// One workgroup per block of SCAN_BLOCK buckets, block frame.path_origin + the workgroup
// (dispatched for the largest bucket count; the blocks past this iteration's count scan zeros
// and store nothing): each invocation scans its SCAN_PER_THREAD counts after the totals of the
// invocations before it.
@compute @workgroup_size(256, 1, 1)
fn grid_scan_blocks(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let buckets = grid_params.mask + 1u;
    let block = frame.path_origin + wid.x;
    let first = 1u + block * SCAN_BLOCK + lid * SCAN_PER_THREAD;
    var v: array<u32, SCAN_PER_THREAD>;
    var total = 0u;
    for (var k = 0u; k < SCAN_PER_THREAD; k++) {
        v[k] = 0u;
        if first + k <= buckets {
            v[k] = atomicLoad(&grid_starts[first + k]);
        }
        total += v[k];
    }
    var running = scan_workgroup(lid, total);
    for (var k = 0u; k < SCAN_PER_THREAD; k++) {
        running += v[k];
        if first + k <= buckets {
            atomicStore(&grid_starts[first + k], running);
        }
    }
    if lid == SCAN_THREADS - 1u && 1u + block * SCAN_BLOCK <= buckets {
        atomicStore(&grid_cursor[block], running);
    }
}

// One workgroup: the inclusive prefix sum of the block totals grid_cursor[0 .. blocks), each
// invocation a contiguous chunk (its total, a scan of the totals in the workgroup, then the
// chunk again).
@compute @workgroup_size(256, 1, 1)
fn grid_scan_sums(@builtin(local_invocation_index) lid: u32) {
    let blocks = (grid_params.mask + SCAN_BLOCK) / SCAN_BLOCK;
    let chunk = (blocks + SCAN_THREADS - 1u) / SCAN_THREADS;
    let first = lid * chunk;
    let end = min(first + chunk, blocks);
    var total = 0u;
    for (var i = first; i < end; i++) {
        total += atomicLoad(&grid_cursor[i]);
    }
    var running = scan_workgroup(lid, total);
    for (var i = first; i < end; i++) {
        running += atomicLoad(&grid_cursor[i]);
        atomicStore(&grid_cursor[i], running);
    }
}

// One workgroup per block after the first, block frame.path_origin + the workgroup: the totals
// of the blocks before it, added to each of its buckets.
@compute @workgroup_size(256, 1, 1)
fn grid_scan_add(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let buckets = grid_params.mask + 1u;
    let block = frame.path_origin + wid.x;
    let first = 1u + block * SCAN_BLOCK + lid * SCAN_PER_THREAD;
    if first > buckets {
        return;
    }
    let before = atomicLoad(&grid_cursor[block - 1u]);
    for (var k = 0u; k < SCAN_PER_THREAD; k++) {
        if first + k <= buckets {
            atomicAdd(&grid_starts[first + k], before);
        }
    }
}

// One invocation per vertex: into its bucket's next slot (the host has copied the starts into
// the cursors).
@compute @workgroup_size(64, 1, 1)
fn grid_scatter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = frame.path_origin + gid.x;
    if i >= grid_params.count {
        return;
    }
    let p = light_vertices[i].p;
    let slot = atomicAdd(&grid_cursor[grid_bucket(p)], 1u);
    grid_entries[slot] = vec4<f32>(p, bitcast<f32>(i));
}

// Whether vertex a comes before vertex b in the CPU's order: by light subpath, then length.
fn vertex_before(a: u32, b: u32) -> bool {
    let va = light_vertices[a];
    let vb = light_vertices[b];
    return va.path < vb.path || (va.path == vb.path && va.length < vb.length);
}

// One invocation per bucket: insertion sort of its entries (a few per bucket).
@compute @workgroup_size(64, 1, 1)
fn grid_sort(@builtin(global_invocation_id) gid: vec3<u32>) {
    let b = frame.path_origin + gid.x;
    if b > grid_params.mask {
        return;
    }
    let start = atomicLoad(&grid_starts[b]);
    let end = atomicLoad(&grid_starts[b + 1u]);
    for (var i = start + 1u; i < end; i++) {
        let e = grid_entries[i];
        var j = i;
        while j > start && vertex_before(bitcast<u32>(e.w), bitcast<u32>(grid_entries[j - 1u].w)) {
            grid_entries[j] = grid_entries[j - 1u];
            j -= 1u;
        }
        grid_entries[j] = e;
    }
}

// One invocation per entry, after grid_sort: the record of its vertex, in entry order
// (PhotonRecord; the CPU's Iteration::build_grid), so that a merge reads 32 bytes beside the
// entries it has just read instead of the vertex wherever the pool holds it.
@compute @workgroup_size(64, 1, 1)
fn grid_records(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = frame.path_origin + gid.x;
    if e >= grid_params.count {
        return;
    }
    photon_records[e] = photon_record(light_vertices[bitcast<u32>(grid_entries[e].w)]);
}

// For tests (`GpuRenderer::grid_check`): per query point i (camera_radiance[i].xyz, i <
// frame.path_count), what merging's search (query_buckets, then the distance test) finds: the
// number of vertices within r, the sum of their indices mod 2^20 and an xor of their hashed
// indices in 23 bits, each an integer below 2^24 so that f32 holds it exactly.
@compute @workgroup_size(64, 1, 1)
fn grid_query_check(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = frame.path_origin + gid.x;
    if i >= frame.path_count {
        return;
    }
    let p = camera_radiance[i].xyz;
    var count = 0u;
    var sum = 0u;
    var mix = 0u;
    let q = query_buckets(p, 1.0);
    for (var j = 0u; j < q.n; j++) {
        let b = q.b[j];
        let end = atomicLoad(&grid_starts[b + 1u]);
        for (var e = atomicLoad(&grid_starts[b]); e < end; e++) {
            let entry = grid_entries[e];
            let d = entry.xyz - p;
            if dot(d, d) < grid_params.radius2 {
                let index = bitcast<u32>(entry.w);
                count += 1u;
                sum += index;
                mix ^= index * 2654435761u;
            }
        }
    }
    camera_radiance[i] = vec4<f32>(f32(count), f32(sum & 0xfffffu), f32(mix >> 9u), 0.0);
}
