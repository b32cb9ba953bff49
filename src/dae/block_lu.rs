//! Block LU of the integrator's iteration matrices along the mechanism's graph.
//!
//! The unknowns come in groups the DAE names (a body's q, u and accelerations; a
//! constraint element's λ and μ; …). The groups are eliminated in a minimum-degree order
//! of the group graph. A group whose rows have no diagonal entries (the multipliers)
//! goes, in the early order, as soon as the bodies eliminated before it can carry its
//! rows (a chain's joint right after its child body, Baraff's order: fronts of one
//! body or one joint), and in the waiting order only once every body it touches is
//! gone, so that its diagonal block is the Schur complement −C D⁻¹ Cᵀ of whole
//! constraint rows (see `analyze`). The early order factors first; a pivot too small
//! there (rows the eliminated bodies could not carry after all) hands that matrix to
//! the waiting order. On a tree of bodies (a chain, a vehicle's suspensions) the work is
//! linear in the number of bodies with dense kernels of the bodies' size, as in
//! Baraff's linear-time Lagrange-multiplier method, here for any matrix with this
//! pattern. Partial pivoting works inside each diagonal block only; a pivot below
//! [`PIVOT_TOL`] times the largest entry of its column fails the factorization in both
//! orders, and the caller falls back to the general sparse LU with row pivoting
//! ([`super::sparse::SparseLu`]).

use super::sparse::LuScalar;
use faer::sparse::Pair;
use std::collections::{BTreeSet, HashMap};
use std::ops::Range;

/// A pivot smaller than this times the largest entry of its column (in the diagonal
/// block, as eliminated so far) fails the block factorization (the general LU with row
/// pivoting then takes the matrix).
pub const PIVOT_TOL: f64 = 1e-12;

/// `$wide $args` (a kernel's AVX2 build) where the CPU has AVX2 ([`wide_vectors`]), else
/// `$base $args` (the baseline build).
macro_rules! wide_or_baseline {
    ($wide:ident, $base:ident, $args:tt) => {{
        #[cfg(target_arch = "x86_64")]
        let r = if wide_vectors() {
            // SAFETY: the CPU has AVX2 (`wide_vectors`).
            unsafe { $wide $args }
        } else {
            $base $args
        };
        #[cfg(not(target_arch = "x86_64"))]
        let r = $base $args;
        r
    }};
}

/// Scratch of an elimination step: its diagonal block, its row blocks side by side,
/// its L column blocks one after the other.
struct Scratch<T> {
    d: Vec<T>,
    u: Vec<T>,
    l: Vec<T>,
}

/// The symbolic part: groups, elimination order, where each block lives.
struct Symbolic {
    n: usize,
    pattern: Vec<Pair<usize, usize>>,
    groups: Vec<usize>,
    /// Group g's unknowns (indices into y) are `vars[start[g]..start[g + 1]]`; its
    /// position in the block-ordered work vector is `start[g]`.
    start: Vec<usize>,
    vars: Vec<usize>,
    /// Per pattern entry: its place in the arena (duplicates share one).
    slot: Vec<usize>,
    /// The eliminations, in order.
    steps: Vec<Step>,
    /// Arena offsets of the blocks each step reads and writes (see [`Step`]).
    offs: Vec<usize>,
    /// The groups still present at each step, concatenated (see [`Step`]).
    later: Vec<usize>,
    arena: usize,
    /// Whether a constraint group went before all of its bodies.
    went_early: bool,
}

/// One group's elimination: its diagonal block at `diag`; its neighbours not yet
/// eliminated are `later[l0..l0 + nl]`; `offs[o0..]` holds, for each neighbour j, the
/// block (k, j), then for each j the block (j, k), then for each pair (i, j) of
/// neighbours the block (i, j) (row-major over i, j).
struct Step {
    k: usize,
    diag: usize,
    l0: usize,
    nl: usize,
    o0: usize,
}

/// A sparse LU by dense blocks of unknown groups (module docs): in the order that takes a
/// constraint group as soon as the bodies eliminated before it can carry its rows, else
/// (a pivot too small in that order, and only for that factorization) in the order that
/// waits for all of its bodies. Reuses its symbolic analyses while the pattern and the
/// groups are unchanged; a refactorization allocates nothing.
pub struct BlockLu<T: LuScalar> {
    /// The early order, then the waiting one (see [`analyze`]).
    orders: [OrderedLu<T>; 2],
    /// Which of `orders` holds the last factorization.
    active: usize,
    /// Number of symbolic analyses performed.
    pub analyses: usize,
}

impl<T: LuScalar> Default for BlockLu<T> {
    fn default() -> Self {
        BlockLu { orders: [OrderedLu::new(true), OrderedLu::new(false)], active: 0, analyses: 0 }
    }
}

impl<T: LuScalar> BlockLu<T> {
    /// Factor the n×n matrix with entries `vals` at `idx` (duplicates summed), unknown i
    /// in group `groups[i]`. Fails (and holds no factorization) when a pivot is too small
    /// for elimination without pivoting between groups in both orders, or a value is not
    /// finite. Which order factors depends on the matrix alone.
    pub fn factor(&mut self, n: usize, idx: &[Pair<usize, usize>], vals: &[T], groups: &[usize]) -> Result<(), String> {
        self.orders[1].factored = false;
        let r = match self.orders[0].factor(n, idx, vals, groups) {
            Ok(()) => {
                self.active = 0;
                Ok(())
            }
            // The early order is the waiting one here: nothing else to try.
            Err(e) if !self.orders[0].sym.as_ref().is_some_and(|s| s.went_early) => Err(e),
            Err(_) => {
                self.active = 1;
                self.orders[1].factor(n, idx, vals, groups)
            }
        };
        self.analyses = self.orders[0].analyses + self.orders[1].analyses;
        r
    }

    /// Solve A x = b in place; false if there is no factorization or the result is not
    /// finite.
    pub fn solve(&mut self, b: &mut [T]) -> bool {
        self.orders[self.active].solve(b)
    }
}

/// The block LU in one elimination order.
struct OrderedLu<T: LuScalar> {
    /// Whether constraint groups go early ([`analyze`]).
    early: bool,
    sym: Option<Symbolic>,
    arena: Vec<T>,
    /// Row interchanges of each diagonal block (LAPACK's ipiv, local indices), by `start`.
    piv: Vec<usize>,
    /// Reciprocals of U's diagonal in each diagonal block, by `start`.
    rdiag: Vec<T>,
    /// Scratch of an elimination step.
    scratch: Scratch<T>,
    /// The work vector of a solve.
    w: Vec<T>,
    factored: bool,
    /// Number of symbolic analyses performed.
    analyses: usize,
}

impl<T: LuScalar> OrderedLu<T> {
    fn new(early: bool) -> Self {
        OrderedLu {
            early,
            sym: None,
            arena: Vec::new(),
            piv: Vec::new(),
            rdiag: Vec::new(),
            scratch: Scratch { d: Vec::new(), u: Vec::new(), l: Vec::new() },
            w: Vec::new(),
            factored: false,
            analyses: 0,
        }
    }

    /// [`BlockLu::factor`] in this order.
    fn factor(&mut self, n: usize, idx: &[Pair<usize, usize>], vals: &[T], groups: &[usize]) -> Result<(), String> {
        self.factored = false;
        let reuse = matches!(&self.sym, Some(s) if s.n == n && s.pattern == idx && s.groups == groups);
        if !reuse {
            let s = analyze(n, idx, groups, self.early)?;
            self.arena = vec![<T as LuScalar>::zero(); s.arena];
            let widest = (0..s.start.len() - 1).map(|g| size(&s, g)).max().unwrap_or(0);
            let wide = s.steps.iter().map(|st| front(&s, st)).max().unwrap_or(0);
            self.piv = vec![0; n];
            self.rdiag = vec![<T as LuScalar>::zero(); n];
            let zero = <T as LuScalar>::zero();
            self.scratch =
                Scratch { d: vec![zero; widest * widest], u: vec![zero; widest * wide], l: vec![zero; widest * wide] };
            self.w = vec![<T as LuScalar>::zero(); n];
            self.sym = Some(s);
            self.analyses += 1;
        }
        let s = self.sym.as_ref().expect("symbolic analysis present");
        if vals.iter().any(|v| !v.finite()) {
            return Err("matrix has non-finite entries".into());
        }
        self.arena.iter_mut().for_each(|v| *v = <T as LuScalar>::zero());
        for (&k, &v) in s.slot.iter().zip(vals) {
            self.arena[k] += v;
        }
        let (a, piv, rdiag, scratch) = (&mut self.arena, &mut self.piv, &mut self.rdiag, &mut self.scratch);
        wide_or_baseline!(eliminate_all_avx2, eliminate_all, (s, a, piv, rdiag, scratch))?;
        self.factored = true;
        Ok(())
    }

    /// [`BlockLu::solve`] in this order.
    fn solve(&mut self, b: &mut [T]) -> bool {
        let Some(s) = self.sym.as_ref().filter(|_| self.factored) else { return false };
        let (a, rdiag, piv, w) = (&self.arena[..], &self.rdiag[..], &self.piv[..], &mut self.w[..]);
        wide_or_baseline!(solve_in_avx2, solve_in, (s, a, rdiag, piv, w, b));
        b.iter().all(|v| v.finite())
    }
}

/// Whether the kernels run in their AVX2 build (4 lanes instead of SSE2's 2; read once
/// per factorization or solve from the CPU, cached by `std`). Without FMA the arithmetic
/// and its rounding are those of the baseline build, so a run gives the same bits on
/// every x86-64 machine.
#[cfg(target_arch = "x86_64")]
#[inline]
fn wide_vectors() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// Every elimination step of the numeric factorization, in order.
#[inline(always)]
fn eliminate_all<T: LuScalar>(
    s: &Symbolic,
    a: &mut [T],
    piv: &mut [usize],
    rdiag: &mut [T],
    scratch: &mut Scratch<T>,
) -> Result<(), String> {
    for st in &s.steps {
        eliminate(s, st, a, piv, rdiag, scratch)?;
    }
    Ok(())
}

/// [`eliminate_all`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn eliminate_all_avx2<T: LuScalar>(
    s: &Symbolic,
    a: &mut [T],
    piv: &mut [usize],
    rdiag: &mut [T],
    scratch: &mut Scratch<T>,
) -> Result<(), String> {
    eliminate_all(s, a, piv, rdiag, scratch)
}

/// The forward and backward sweeps of a solve of the factorization (`a`, `rdiag`,
/// `piv`) in the work vector `w`, b in place.
#[inline(always)]
fn solve_in<T: LuScalar>(s: &Symbolic, a: &[T], rdiag: &[T], piv: &[usize], w: &mut [T], b: &mut [T]) {
    for (p, &v) in s.vars.iter().enumerate() {
        w[p] = b[v];
    }
    // Forward: w_i −= L_ik w_k for the groups still present after k.
    for st in &s.steps {
        let (k0, sk) = (s.start[st.k], size(s, st.k));
        for j in 0..st.nl {
            let i = s.later[st.l0 + j];
            let (i0, si) = (s.start[i], size(s, i));
            let off = s.offs[st.o0 + st.nl + j];
            let (y, x) = split_two(w, i0..i0 + si, k0..k0 + sk);
            gemv_sub(y, &a[off..off + si * sk], x, false);
        }
    }
    // Backward: w_k ← D_kk⁻¹ (w_k − Σ_j A_kj w_j), D_kk⁻¹ = U⁻¹ L⁻¹ P.
    for st in s.steps.iter().rev() {
        let (k0, sk) = (s.start[st.k], size(s, st.k));
        for j in 0..st.nl {
            let g = s.later[st.l0 + j];
            let (g0, sg) = (s.start[g], size(s, g));
            let off = s.offs[st.o0 + j];
            let (y, x) = split_two(w, k0..k0 + sk, g0..g0 + sg);
            gemv_sub(y, &a[off..off + sk * sg], x, false);
        }
        let dg = &a[st.diag..st.diag + sk * sk];
        block_solve(dg, &rdiag[k0..k0 + sk], &piv[k0..k0 + sk], &mut w[k0..k0 + sk]);
    }
    for (p, &v) in s.vars.iter().enumerate() {
        b[v] = w[p];
    }
}

/// [`solve_in`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn solve_in_avx2<T: LuScalar>(s: &Symbolic, a: &[T], rdiag: &[T], piv: &[usize], w: &mut [T], b: &mut [T]) {
    solve_in(s, a, rdiag, piv, w, b);
}

#[inline(always)]
fn size(s: &Symbolic, g: usize) -> usize {
    s.start[g + 1] - s.start[g]
}

/// The unknowns of the groups still present at step `st` (its front).
fn front(s: &Symbolic, st: &Step) -> usize {
    (0..st.nl).map(|j| size(s, s.later[st.l0 + j])).sum()
}

/// Eliminate one group (block Gaussian elimination: the row blocks A_kj stay as they
/// are): the LU of its diagonal block D_kk (partial pivoting inside it, its pivots
/// checked, the reciprocals of U's diagonal kept), its L column blocks L_ik = A_ik D_kk⁻¹
/// and the Schur updates A_ij −= L_ik A_kj of the groups still present. The forward
/// solve is then one product per block, and no solve divides.
#[inline(always)]
fn eliminate<T: LuScalar>(
    s: &Symbolic,
    st: &Step,
    a: &mut [T],
    piv: &mut [usize],
    rdiag: &mut [T],
    scratch: &mut Scratch<T>,
) -> Result<(), String> {
    let Scratch { d, u, l } = scratch;
    let (k0, sk) = (s.start[st.k], size(s, st.k));
    let d = &mut d[..sk * sk];
    d.copy_from_slice(&a[st.diag..st.diag + sk * sk]);
    let piv = &mut piv[k0..k0 + sk];
    lu_in_place(d, sk, piv)?;
    a[st.diag..st.diag + sk * sk].copy_from_slice(d);
    for (c, r) in rdiag[k0..k0 + sk].iter_mut().enumerate() {
        *r = <T as LuScalar>::one() / d[c + c * sk];
    }
    let rd = &rdiag[k0..k0 + sk];
    let nbr = &s.later[st.l0..st.l0 + st.nl];
    let offs = &s.offs[st.o0..];
    // The row blocks A_kj side by side in `u` (sk × Σ sj, column-major); L_ik = A_ik D⁻¹
    // = A_ik U⁻¹ L⁻¹ P (si × sk) in the arena and one after the other in `l`.
    let mut ucol = 0;
    let mut lpos = 0;
    for (j, &g) in nbr.iter().enumerate() {
        let sg = size(s, g);
        let (okj, ojk) = (offs[j], offs[st.nl + j]);
        u[ucol * sk..(ucol + sg) * sk].copy_from_slice(&a[okj..okj + sg * sk]);
        ucol += sg;
        let blk = &mut a[ojk..ojk + sg * sk];
        // X = A_ik U⁻¹, column by column.
        for c in 0..sk {
            let (left, right) = blk.split_at_mut(c * sg);
            let out = &mut right[..sg];
            for p in 0..c {
                let upc = d[p + c * sk];
                if !upc.is_zero() {
                    axpy(out, &left[p * sg..(p + 1) * sg], upc);
                }
            }
            let inv = rd[c];
            out.iter_mut().for_each(|v| *v *= inv);
        }
        // Y = X L⁻¹, the last column first.
        for c in (0..sk).rev() {
            let (left, right) = blk.split_at_mut((c + 1) * sg);
            let out = &mut left[c * sg..];
            for p in c + 1..sk {
                let lpc = d[p + c * sk];
                if !lpc.is_zero() {
                    axpy(out, &right[(p - c - 1) * sg..(p - c) * sg], lpc);
                }
            }
        }
        // L_ik = Y P: the interchanges as column swaps, the last first.
        for c in (0..sk).rev() {
            let p = piv[c];
            if p != c {
                for r in 0..sg {
                    blk.swap(r + c * sg, r + p * sg);
                }
            }
        }
        l[lpos..lpos + sg * sk].copy_from_slice(blk);
        lpos += sg * sk;
    }
    // A_ij −= L_ik A_kj (the zeros of A_kj skipped: a body's position rows do not touch
    // the multipliers its velocity rows do).
    let mut lpos = 0;
    for (i, &gi) in nbr.iter().enumerate() {
        let si = size(s, gi);
        let li = &l[lpos..lpos + si * sk];
        let mut ucol = 0;
        for (j, &gj) in nbr.iter().enumerate() {
            let sj = size(s, gj);
            let oij = offs[2 * st.nl + i * st.nl + j];
            let blk = &mut a[oij..oij + si * sj];
            for (c, out) in blk.chunks_exact_mut(si).enumerate() {
                gemv_sub(out, li, &u[(ucol + c) * sk..(ucol + c + 1) * sk], true);
            }
            ucol += sj;
        }
        lpos += si * sk;
    }
    Ok(())
}

/// y −= x·a.
#[inline(always)]
fn axpy<T: LuScalar>(y: &mut [T], x: &[T], a: T) {
    for (o, &v) in y.iter_mut().zip(x) {
        *o -= v * a;
    }
}

/// The disjoint ranges `y` (mutable) and `x` of `w`.
#[inline(always)]
fn split_two<T>(w: &mut [T], y: Range<usize>, x: Range<usize>) -> (&mut [T], &[T]) {
    if y.start >= x.end {
        let (lo, hi) = w.split_at_mut(y.start);
        (&mut hi[..y.len()], &lo[x])
    } else {
        let (lo, hi) = w.split_at_mut(x.start);
        (&mut lo[y], &hi[..x.len()])
    }
}

/// Calls `$f::<T, N>` for the sizes of `$n` listed, else `$g` (the same arithmetic in
/// the same order; the fixed sizes keep the vector in registers).
macro_rules! by_size {
    ($n:expr, $f:ident, $g:ident, $args:tt, [$($k:literal),*]) => {
        match $n {
            $($k => $f::<T, $k> $args,)*
            _ => $g $args,
        }
    };
}

/// y −= A x for the column-major len(y) × len(x) block `a`; with `skip_zeros` the
/// columns of the zero entries of x are not read (structural zeros of a factorization).
#[inline(always)]
fn gemv_sub<T: LuScalar>(y: &mut [T], a: &[T], x: &[T], skip_zeros: bool) {
    by_size!(y.len(), gemv_sub_n, gemv_sub_any, (y, a, x, skip_zeros), [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
}

#[inline(always)]
fn gemv_sub_n<T: LuScalar, const N: usize>(y: &mut [T], a: &[T], x: &[T], skip_zeros: bool) {
    let y: &mut [T; N] = y.try_into().expect("block of N rows");
    let mut acc = *y;
    for (col, &v) in a.chunks_exact(N).zip(x) {
        if skip_zeros && v.is_zero() {
            continue;
        }
        let col: &[T; N] = col.try_into().expect("column of N");
        for r in 0..N {
            acc[r] -= col[r] * v;
        }
    }
    *y = acc;
}

#[inline(always)]
fn gemv_sub_any<T: LuScalar>(y: &mut [T], a: &[T], x: &[T], skip_zeros: bool) {
    for (col, &v) in a.chunks_exact(y.len()).zip(x) {
        if !(skip_zeros && v.is_zero()) {
            axpy(y, col, v);
        }
    }
}

/// x ← D⁻¹ x = U⁻¹ L⁻¹ P x for the LU `lu` of a diagonal block (column-major, as
/// [`lu_in_place`] leaves it) with row interchanges `piv` and U's reciprocal pivots `rd`.
#[inline(always)]
fn block_solve<T: LuScalar>(lu: &[T], rd: &[T], piv: &[usize], x: &mut [T]) {
    by_size!(x.len(), block_solve_n, block_solve_any, (lu, rd, piv, x), [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
}

#[inline(always)]
fn block_solve_n<T: LuScalar, const N: usize>(lu: &[T], rd: &[T], piv: &[usize], x: &mut [T]) {
    let xs: &mut [T; N] = x.try_into().expect("block of N");
    let mut v = *xs;
    for (c, &p) in piv.iter().enumerate().take(N) {
        v.swap(c, p);
    }
    for c in 0..N {
        let xc = v[c];
        for r in c + 1..N {
            v[r] -= lu[r + c * N] * xc;
        }
    }
    for c in (0..N).rev() {
        let xc = v[c] * rd[c];
        v[c] = xc;
        for r in 0..c {
            v[r] -= lu[r + c * N] * xc;
        }
    }
    *xs = v;
}

#[inline(always)]
fn block_solve_any<T: LuScalar>(lu: &[T], rd: &[T], piv: &[usize], x: &mut [T]) {
    let s = x.len();
    for (c, &p) in piv.iter().enumerate() {
        x.swap(c, p);
    }
    for c in 0..s {
        let v = x[c];
        axpy(&mut x[c + 1..s], &lu[c * s + c + 1..(c + 1) * s], v);
    }
    for c in (0..s).rev() {
        let v = x[c] * rd[c];
        x[c] = v;
        axpy(&mut x[..c], &lu[c * s..c * s + c], v);
    }
}

/// Dense LU with partial pivoting of the column-major s×s matrix `d` in place
/// (unit L below, U on and above the diagonal); `piv[c]` is the row swapped with row c.
#[inline(always)]
fn lu_in_place<T: LuScalar>(d: &mut [T], s: usize, piv: &mut [usize]) -> Result<(), String> {
    for c in 0..s {
        // The column's largest entry before elimination: a pivot is small against its
        // own column (a flexible body's stiffness rows are 10¹³ times its rigid inertia).
        let big = d[c * s..(c + 1) * s].iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
        let (mut p, mut best) = (c, d[c + c * s].magnitude());
        for r in c + 1..s {
            let v = d[r + c * s].magnitude();
            if v > best {
                (p, best) = (r, v);
            }
        }
        if best <= PIVOT_TOL * big || best == 0.0 {
            return Err(format!("pivot {best:e} below {PIVOT_TOL:e} of its column's largest entry {big:e}"));
        }
        piv[c] = p;
        if p != c {
            for cc in 0..s {
                d.swap(c + cc * s, p + cc * s);
            }
        }
        let inv = <T as LuScalar>::one() / d[c + c * s];
        d[c * s + c + 1..(c + 1) * s].iter_mut().for_each(|v| *v *= inv);
        let (left, right) = d.split_at_mut((c + 1) * s);
        let lcol = &left[c * s + c + 1..];
        for col in right.chunks_exact_mut(s) {
            let x = col[c];
            if !x.is_zero() {
                axpy(&mut col[c + 1..], lcol, x);
            }
        }
    }
    Ok(())
}

/// The symbolic analysis: groups, their graph, the elimination order, the blocks of the
/// filled pattern and the arena places of the entries.
fn analyze(n: usize, idx: &[Pair<usize, usize>], groups: &[usize], early: bool) -> Result<Symbolic, String> {
    if groups.len() != n {
        return Err(format!("{} groups for {n} unknowns", groups.len()));
    }
    let ng = groups.iter().max().map_or(0, |g| g + 1);
    let mut start = vec![0usize; ng + 1];
    for &g in groups {
        start[g + 1] += 1;
    }
    for g in 0..ng {
        start[g + 1] += start[g];
    }
    let mut fill = start.clone();
    let mut vars = vec![0; n];
    let mut local = vec![0; n];
    for (i, &g) in groups.iter().enumerate() {
        local[i] = fill[g] - start[g];
        vars[fill[g]] = i;
        fill[g] += 1;
    }
    let sz = |g: usize| start[g + 1] - start[g];
    let mut adj: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); ng];
    let mut diag = vec![false; n];
    for p in idx {
        if p.row >= n || p.col >= n {
            return Err("entry outside the matrix".into());
        }
        let (gr, gc) = (groups[p.row], groups[p.col]);
        if gr != gc {
            adj[gr].insert(gc);
            adj[gc].insert(gr);
        } else if p.row == p.col {
            diag[p.row] = true;
        }
    }
    // A group whose unknowns all have diagonal entries (a body) may go at any time. One
    // without (a constraint element's multipliers) waits until every such group it
    // touches is gone: the eliminated set is then [D Cᵀ; C 0] with all the rows C of its
    // constraint groups, nonsingular for D near γ/h M and constraints of full row rank,
    // whatever the order. (Taken after one body only, a ground joint can use up that
    // body's freedom before the body's next joint comes: a four-bar's crank pin.)
    let full: Vec<bool> = (0..ng).map(|g| vars[start[g]..start[g + 1]].iter().all(|&v| diag[v])).collect();
    let mut waiting: Vec<usize> =
        (0..ng).map(|g| if full[g] { 0 } else { adj[g].iter().filter(|&&j| full[j]).count() }).collect();
    let touches: Vec<Vec<usize>> = (0..ng)
        .map(|g| if full[g] { adj[g].iter().copied().filter(|&j| !full[j]).collect() } else { Vec::new() })
        .collect();
    //
    // In the early order a constraint group may also go once it is the only constraint
    // group left that the eliminated groups it is joined to (through eliminations:
    // `cluster`) touch (`pending`), and those have more unknowns left (`free`: their
    // bodies' unknowns less their constraint groups') than it has (more, not as many: a
    // group of velocity rows alone, a rolling wheel's, takes no position freedom, so an
    // exact count can still leave too few velocities): along a tree from its leaves,
    // each joint right after its child body, as in Baraff's order.
    // The fronts then hold one body or one joint instead of a body and its joints (and,
    // with the cross-body terms of the exact J, a neighbour body). A joint whose rows the
    // eliminated bodies cannot carry makes a pivot too small, and the waiting order
    // factors that matrix instead (`BlockLu::factor`).
    let degree = |adj: &BTreeSet<usize>| adj.iter().map(|&j| sz(j)).sum::<usize>();
    let mut deg: Vec<usize> = adj.iter().map(degree).collect();
    let mut cluster: Vec<usize> = (0..ng).collect();
    let mut free = vec![0isize; ng];
    let mut pending = vec![0usize; ng];
    let mut attached: Vec<Vec<usize>> = vec![Vec::new(); ng];
    fn root(cluster: &mut [usize], mut g: usize) -> usize {
        while cluster[g] != g {
            cluster[g] = cluster[cluster[g]];
            g = cluster[g];
        }
        g
    }
    let mut roots = Vec::new();
    let attached_roots = |g: usize, cluster: &mut [usize], attached: &[Vec<usize>], roots: &mut Vec<usize>| {
        roots.clear();
        roots.extend(attached[g].iter().map(|&r| root(cluster, r)));
        roots.sort_unstable();
        roots.dedup();
    };
    let mut went_early = false;
    let mut queue: BTreeSet<(usize, usize)> =
        (0..ng).filter(|&g| waiting[g] == 0 && sz(g) > 0).map(|g| (deg[g], g)).collect();
    let mut order = Vec::with_capacity(ng);
    let mut later_sets = Vec::with_capacity(ng);
    while let Some((_, k)) = queue.pop_first() {
        let nbr: Vec<usize> = adj[k].iter().copied().collect();
        for &i in &nbr {
            adj[i].remove(&k);
            for &j in &nbr {
                if i != j {
                    adj[i].insert(j);
                }
            }
        }
        for &i in &touches[k] {
            waiting[i] -= 1;
        }
        went_early |= !full[k] && waiting[k] > 0;
        attached_roots(k, &mut cluster, &attached, &mut roots);
        let own = if full[k] { sz(k) as isize } else { -(sz(k) as isize) };
        free[k] = own + roots.iter().map(|&r| free[r]).sum::<isize>();
        // The constraint groups any of the merged groups touch are k's neighbours now.
        pending[k] = nbr.iter().filter(|&&i| !full[i]).count();
        for &r in &roots {
            cluster[r] = k;
        }
        for &i in &nbr {
            attached[i].push(k);
            queue.remove(&(deg[i], i));
            deg[i] = degree(&adj[i]);
            let carried = early && !full[i] && {
                attached_roots(i, &mut cluster, &attached, &mut roots);
                roots.iter().all(|&r| pending[r] == 1) && roots.iter().map(|&r| free[r]).sum::<isize>() > sz(i) as isize
            };
            if waiting[i] == 0 || carried {
                queue.insert((deg[i], i));
            }
        }
        order.push(k);
        later_sets.push(nbr);
    }
    debug_assert_eq!(order.len(), (0..ng).filter(|&g| sz(g) > 0).count(), "every group eliminated");
    // Arena: every block a step touches.
    let mut place: HashMap<(usize, usize), usize> = HashMap::new();
    let mut arena = 0usize;
    let mut at = |i: usize, j: usize, place: &mut HashMap<(usize, usize), usize>| -> usize {
        *place.entry((i, j)).or_insert_with(|| {
            let o = arena;
            arena += sz(i) * sz(j);
            o
        })
    };
    let (mut steps, mut offs, mut later) = (Vec::with_capacity(ng), Vec::new(), Vec::new());
    for (&k, nbr) in order.iter().zip(&later_sets) {
        let diag = at(k, k, &mut place);
        let (l0, o0) = (later.len(), offs.len());
        later.extend_from_slice(nbr);
        for &j in nbr {
            offs.push(at(k, j, &mut place));
        }
        for &j in nbr {
            offs.push(at(j, k, &mut place));
        }
        for &i in nbr {
            for &j in nbr {
                offs.push(at(i, j, &mut place));
            }
        }
        steps.push(Step { k, diag, l0, nl: nbr.len(), o0 });
    }
    let slot = idx
        .iter()
        .map(|p| {
            let (gr, gc) = (groups[p.row], groups[p.col]);
            place[&(gr, gc)] + local[p.row] + local[p.col] * sz(gr)
        })
        .collect();
    Ok(Symbolic {
        n,
        pattern: idx.to_vec(),
        groups: groups.to_vec(),
        start,
        vars,
        slot,
        steps,
        offs,
        later,
        arena,
        went_early,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dae::sparse::SparseLu;
    use faer::c64;

    /// n, the entries, their values, the groups.
    type Chain = (usize, Vec<Pair<usize, usize>>, Vec<f64>, Vec<usize>);

    /// A chain of `nb` "bodies" (3 unknowns each, diagonally dominant) joined by
    /// 2-row "constraints" with zero diagonal blocks, plus a loop-closing constraint
    /// between the last body and the first: the pattern of a closed chain's KKT-like
    /// iteration matrix.
    fn chain(nb: usize, close: bool) -> Chain {
        let nj = if close { nb } else { nb - 1 };
        let n = 3 * nb + 2 * nj;
        let (mut idx, mut vals, mut groups) = (Vec::new(), Vec::new(), vec![0; n]);
        let mut rnd = 0.123_f64;
        let mut next = || {
            rnd = (rnd * 3.7 + 0.31).fract();
            rnd - 0.5
        };
        for b in 0..nb {
            for r in 0..3 {
                groups[3 * b + r] = b;
                for c in 0..3 {
                    idx.push(Pair::new(3 * b + r, 3 * b + c));
                    vals.push(if r == c { 4.0 } else { next() });
                }
            }
        }
        for j in 0..nj {
            let row = 3 * nb + 2 * j;
            let (b1, b2) = (j, (j + 1) % nb);
            for r in 0..2 {
                groups[row + r] = nb + j;
                for b in [b1, b2] {
                    for c in 0..3 {
                        let v = next() + if c == r { 1.0 } else { 0.0 };
                        idx.push(Pair::new(row + r, 3 * b + c));
                        vals.push(v);
                        idx.push(Pair::new(3 * b + c, row + r));
                        vals.push(v + 0.1 * next());
                    }
                }
            }
        }
        (n, idx, vals, groups)
    }

    /// The largest difference of x from the solution of A x = b by the independent
    /// general LU (row pivoting).
    fn off_general(n: usize, idx: &[Pair<usize, usize>], vals: &[f64], x: &[f64], b: &[f64]) -> f64 {
        let mut glu = SparseLu::<f64>::default();
        glu.factor_values(n, idx, vals).expect("general LU");
        let mut xg = b.to_vec();
        assert!(glu.solve(&mut xg));
        x.iter().zip(&xg).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
    }

    fn residual(n: usize, idx: &[Pair<usize, usize>], vals: &[f64], x: &[f64], b: &[f64]) -> f64 {
        let mut ax = vec![0.0; n];
        for (p, v) in idx.iter().zip(vals) {
            ax[p.row] += v * x[p.col];
        }
        ax.iter().zip(b).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
    }

    #[test]
    fn solves_open_and_closed_chains_as_the_general_lu_does() {
        for close in [false, true] {
            let (n, idx, vals, groups) = chain(30, close);
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let mut blu = BlockLu::<f64>::default();
            blu.factor(n, &idx, &vals, &groups).expect("block LU");
            let mut x = b.clone();
            assert!(blu.solve(&mut x));
            // Against the independent general LU (row pivoting): the same solution to
            // round-off of this well-conditioned matrix, and a residual at round-off.
            let diff = off_general(n, &idx, &vals, &x, &b);
            assert!(diff < 1e-11, "close {close}: differs from the general LU by {diff:e}");
            assert!(residual(n, &idx, &vals, &x, &b) < 1e-12);
            // A refactorization with new values reuses the analysis.
            let vals2: Vec<f64> = vals.iter().map(|v| v * 1.5).collect();
            blu.factor(n, &idx, &vals2, &groups).expect("block LU");
            let mut x2 = b.clone();
            assert!(blu.solve(&mut x2));
            assert!(residual(n, &idx, &vals2, &x2, &b) < 1e-12);
            assert_eq!(blu.analyses, 1);
        }
    }

    /// The fixed-size kernels do the generic ones' arithmetic in the same order (bit for
    /// bit) at every size they cover, and the block solve inverts the block: D (D⁻¹ b) = b
    /// to round-off (1e-13 on these well-conditioned blocks with |D| ~ 1) at sizes 1 to 14
    /// (13 and 14 take the generic path).
    #[test]
    fn fixed_size_kernels_match_the_generic_ones_bit_for_bit() {
        for n in 1..=14usize {
            let m = n + 3;
            let a: Vec<f64> = (0..n * m).map(|i| ((i * 37 % 101) as f64 / 50.0 - 1.0) * 0.7).collect();
            let x: Vec<f64> = (0..m).map(|i| if i % 4 == 1 { 0.0 } else { (i as f64 * 0.61).sin() }).collect();
            let y0: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3).cos()).collect();
            let (mut y1, mut y2, mut y3, mut y4) = (y0.clone(), y0.clone(), y0.clone(), y0.clone());
            gemv_sub(&mut y1, &a, &x, false);
            gemv_sub_any(&mut y2, &a, &x, false);
            gemv_sub(&mut y3, &a, &x, true);
            gemv_sub_any(&mut y4, &a, &x, true);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&y1), bits(&y2), "gemv, n = {n}");
            assert_eq!(bits(&y3), bits(&y4), "gemv skipping zeros, n = {n}");
            // A block that needs row interchanges: small diagonal, larger entries below.
            let d: Vec<f64> =
                (0..n * n).map(|i| if i % (n + 1) == 0 { 0.1 } else { (i * 53 % 97) as f64 / 48.0 - 1.0 }).collect();
            let mut lu = d.clone();
            let mut piv = vec![0; n];
            lu_in_place(&mut lu, n, &mut piv).expect("nonsingular block");
            let rd: Vec<f64> = (0..n).map(|c| 1.0 / lu[c + c * n]).collect();
            let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 * 0.25).collect();
            let (mut x1, mut x2) = (b.clone(), b.clone());
            block_solve(&lu, &rd, &piv, &mut x1);
            block_solve_any(&lu, &rd, &piv, &mut x2);
            assert_eq!(bits(&x1), bits(&x2), "block solve, n = {n}");
            for r in 0..n {
                let dx: f64 = (0..n).map(|c| d[r + c * n] * x1[c]).sum();
                assert!((dx - b[r]).abs() < 1e-13 * (1.0 + x1.iter().fold(0.0f64, |m, v| m.max(v.abs()))), "n = {n}");
            }
        }
    }

    /// The factorization and solve of the CPU's build (AVX2 where it has it) give the
    /// bits of the baseline build, real and complex: a run does not depend on the
    /// machine's vector width.
    #[test]
    fn the_wide_vector_build_gives_the_baseline_bits() {
        fn check<T: LuScalar + std::fmt::Debug>(to: impl Fn(usize, f64) -> T, bits: impl Fn(&[T]) -> Vec<u64>) {
            let (n, idx, vals, groups) = chain(25, true);
            let vals: Vec<T> = vals.iter().enumerate().map(|(i, &v)| to(i, v)).collect();
            let mut blu = BlockLu::<T>::default();
            blu.factor(n, &idx, &vals, &groups).expect("block LU");
            let b: Vec<T> = (0..n).map(|i| to(i + 7, (i as f64 * 0.37).sin())).collect();
            let mut x = b.clone();
            assert!(blu.solve(&mut x));
            // The baseline build of the numeric factorization, from the same entries.
            let blu = &blu.orders[blu.active];
            let s = blu.sym.as_ref().expect("analysed");
            let mut a = vec![<T as LuScalar>::zero(); s.arena];
            for (&k, &v) in s.slot.iter().zip(&vals) {
                a[k] += v;
            }
            let (mut piv, mut rdiag) = (vec![0; n], vec![<T as LuScalar>::zero(); n]);
            let zero = <T as LuScalar>::zero();
            let big = blu.scratch.d.len().max(blu.scratch.u.len()).max(blu.scratch.l.len());
            let mut scratch = Scratch { d: vec![zero; big], u: vec![zero; big], l: vec![zero; big] };
            eliminate_all(s, &mut a, &mut piv, &mut rdiag, &mut scratch).expect("baseline factorization");
            assert_eq!(bits(&a), bits(&blu.arena), "factors");
            assert_eq!(piv, blu.piv);
            let (mut xb, mut w) = (b.clone(), vec![zero; n]);
            solve_in(s, &a, &rdiag, &piv, &mut w, &mut xb);
            assert_eq!(bits(&xb), bits(&x), "solution");
        }
        check(|_, v| v, |v: &[f64]| v.iter().map(|x| x.to_bits()).collect());
        check(
            |i, v| c64::new(v, 0.3 * (i as f64).cos()),
            |v: &[c64]| v.iter().flat_map(|x| [x.re.to_bits(), x.im.to_bits()]).collect(),
        );
    }

    /// The sum over the elimination steps of the unknowns in their fronts.
    fn fronts(s: &Symbolic) -> usize {
        s.steps.iter().map(|st| front(s, st)).sum()
    }

    #[test]
    fn an_open_chain_goes_in_the_early_order_with_narrower_fronts() {
        let (n, idx, vals, groups) = chain(30, false);
        let mut blu = BlockLu::<f64>::default();
        blu.factor(n, &idx, &vals, &groups).expect("block LU");
        assert_eq!(blu.active, 0, "the early order factors an open chain");
        let early = blu.orders[0].sym.as_ref().unwrap();
        assert!(early.went_early, "a constraint group went before both of its bodies");
        // From an end: each body's front is its one remaining constraint (2 unknowns),
        // each constraint's its other body (3), at most 2·30 + 3·29 in all; waiting, a
        // body meets both of its constraints.
        let waiting = analyze(n, &idx, &groups, false).unwrap();
        assert!(!waiting.went_early);
        assert!(fronts(early) <= 2 * 30 + 3 * 29, "{}", fronts(early));
        assert!(fronts(early) < fronts(&waiting), "{} vs {}", fronts(early), fronts(&waiting));
        assert_eq!(blu.analyses, 1, "the waiting order was not needed");
    }

    #[test]
    fn a_constraint_the_bodies_before_it_cannot_carry_goes_to_the_waiting_order() {
        // Three bodies in a row; the first constraint's two rows are equal on the first
        // body's columns, so after that body alone its block −C D⁻¹ Cᵀ has rank 1, and
        // the early order (body 2, its constraint, body 0, then this constraint) fails.
        let (n, idx, mut vals, groups) = chain(3, false);
        let row = 9;
        let at: HashMap<(usize, usize), usize> = idx.iter().enumerate().map(|(k, p)| ((p.row, p.col), k)).collect();
        for c in 0..3 {
            vals[at[&(row + 1, c)]] = vals[at[&(row, c)]];
            vals[at[&(c, row + 1)]] = vals[at[&(c, row)]];
        }
        let mut blu = BlockLu::<f64>::default();
        blu.factor(n, &idx, &vals, &groups).expect("the waiting order factors it");
        assert_eq!(blu.active, 1);
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).cos()).collect();
        let mut x = b.clone();
        assert!(blu.solve(&mut x));
        // Against the general LU with row pivoting (this matrix is nonsingular: the
        // second body's columns give the constraint full rank).
        let diff = off_general(n, &idx, &vals, &x, &b);
        assert!(diff < 1e-10, "differs from the general LU by {diff:e}");
        assert!(residual(n, &idx, &vals, &x, &b) < 1e-12);
        // The order follows the matrix alone: the regular chain goes early again.
        let (_, _, regular, _) = chain(3, false);
        blu.factor(n, &idx, &regular, &groups).expect("block LU");
        assert_eq!(blu.active, 0);
        assert_eq!(blu.analyses, 2, "each order analysed once");
    }

    #[test]
    fn complex_values_solve_to_round_off() {
        let (n, idx, vals, groups) = chain(12, true);
        let cv: Vec<c64> = vals.iter().enumerate().map(|(i, &v)| c64::new(v, 0.3 * (i as f64).cos())).collect();
        let mut blu = BlockLu::<c64>::default();
        blu.factor(n, &idx, &cv, &groups).expect("block LU");
        let b: Vec<c64> = (0..n).map(|i| c64::new(1.0, i as f64 * 0.1)).collect();
        let mut x = b.clone();
        assert!(blu.solve(&mut x));
        let mut ax = vec![c64::new(0.0, 0.0); n];
        for (p, v) in idx.iter().zip(&cv) {
            ax[p.row] += *v * x[p.col];
        }
        let r = ax.iter().zip(&b).map(|(a, b)| (*a - *b).norm()).fold(0.0, f64::max);
        assert!(r < 1e-12, "residual {r:e}");
    }

    #[test]
    fn a_block_that_needs_pivoting_between_groups_is_refused() {
        // Two singleton groups [[0, 1], [1, 0]]: each diagonal block is zero, only a row
        // interchange across the groups factors it.
        let idx = vec![Pair::new(0, 1), Pair::new(1, 0), Pair::new(0, 0), Pair::new(1, 1)];
        let vals = vec![1.0, 1.0, 0.0, 0.0];
        let mut blu = BlockLu::<f64>::default();
        let err = blu.factor(2, &idx, &vals, &[0, 1]).unwrap_err();
        assert!(err.contains("zero diagonal block") || err.contains("pivot"), "{err}");
        let mut x = vec![1.0, 2.0];
        assert!(!blu.solve(&mut x), "no factorization is held after a failure");
        // In one group the block pivots inside: x = [2, 1].
        blu.factor(2, &idx, &vals, &[0, 0]).expect("one group");
        assert!(blu.solve(&mut x));
        assert_eq!(x, vec![2.0, 1.0]);
    }
}
