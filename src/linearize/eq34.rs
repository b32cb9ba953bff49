//! The layout of the augmented sensitivity system (seed Eq. 34a–34k, Table 1): its blocks
//! of unknowns and of equations, in order, with their sizes. Every offset into Eq. 34 is
//! computed here and nowhere else.
//!
//! The seed's system is generalized to s0 position states S, s1 ≤ s0 velocity states W,
//! mn non-holonomic equations (multipliers ν), redundant constraint rows (m − mr of them:
//! their λ = 0, their equations left out), and the user unknowns Z = (X, Ẋ, V, a) with
//! their rows (Eq. 7a–7b).

/// A block of unknowns (columns) of Eq. 34, in column order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unknown {
    /// u̇ (n).
    UDot,
    /// q̇ (n).
    QDot,
    /// Ẇ (s1).
    WDot,
    /// Ṡ (s0).
    SDot,
    /// λ (m), directly followed by ν.
    Lambda,
    /// ν (mn).
    Nu,
    /// u (n).
    U,
    /// q (n).
    Q,
    /// W (s1).
    W,
    /// S (s0).
    S,
    /// Z = (X, Ẋ, V, a) (nz).
    Z,
}

/// A block of equations (rows) of Eq. 34, in row order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Equation {
    /// Eq. 34a: M u̇ − (Q − Pᵀλ − Bᵀν) = 0 (n rows; u̇ = a for a body with acceleration
    /// unknowns, whose force balance is a user row).
    Eq34a,
    /// Eq. 34b: q̇ − H(q) u = 0 (n).
    Eq34b,
    /// Eq. 34c: C̈(u̇, u, q, t) = 0 (m; λ = 0 on a redundant row), then ġ = 0 (mn).
    Eq34c,
    /// Eq. 34d: Ċ = P u + C_t = 0 (mr independent rows), then g = B u + b = 0 (mn).
    Eq34d,
    /// Eq. 34e: C(q, t) = 0 (mr independent rows).
    Eq34e,
    /// Eq. 34f: S − s(q, t) = 0 (s0).
    Eq34f,
    /// Eq. 34g: Ṡ − ṡ(q, u, t) = 0 (s0).
    Eq34g,
    /// Eq. 34h: W − w(q, u, t) = 0 (s1).
    Eq34h,
    /// Eq. 34i: Ẇ − ẇ(q, u, u̇, t) = 0 (s1).
    Eq34i,
    /// Eq. 34j: W = W̄ (s1; the virtual velocity states).
    Eq34j,
    /// Eq. 34k: S = S̄ (s0; the virtual position states).
    Eq34k,
    /// Eq. 7a–7b: the user rows r(q, u, Z, v, t) = 0 (nz − nx: Ẋ, V, then the force
    /// balances of bodies with acceleration unknowns).
    Eq7,
    /// X = X̄ (nx): the differential states' own virtual states.
    XBar,
}

const UNKNOWNS: [Unknown; 11] = {
    use Unknown::*;
    [UDot, QDot, WDot, SDot, Lambda, Nu, U, Q, W, S, Z]
};

const EQUATIONS: [Equation; 13] = {
    use Equation::*;
    [Eq34a, Eq34b, Eq34c, Eq34d, Eq34e, Eq34f, Eq34g, Eq34h, Eq34i, Eq34j, Eq34k, Eq7, XBar]
};

/// The sizes that fix the layout of Eq. 34.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Eq34 {
    /// Coordinates n.
    pub n: usize,
    /// Holonomic constraint rows m.
    pub m: usize,
    /// Independent holonomic rows mr (m minus the redundant ones).
    pub mr: usize,
    /// Non-holonomic rows mn.
    pub mn: usize,
    /// Position states s0 = n − mr.
    pub s0: usize,
    /// Velocity states s1 = s0 − mn.
    pub s1: usize,
    /// Differential states X.
    pub nx: usize,
    /// User unknowns Z = (X, Ẋ, V, a).
    pub nz: usize,
}

impl Eq34 {
    /// Number of unknowns in block `u`.
    pub fn size_of(&self, u: Unknown) -> usize {
        use Unknown::*;
        match u {
            UDot | QDot | U | Q => self.n,
            WDot | W => self.s1,
            SDot | S => self.s0,
            Lambda => self.m,
            Nu => self.mn,
            Z => self.nz,
        }
    }

    /// Number of equations in block `e`.
    pub fn rows_of(&self, e: Equation) -> usize {
        use Equation::*;
        match e {
            Eq34a | Eq34b => self.n,
            Eq34c => self.m + self.mn,
            Eq34d => self.mr + self.mn,
            Eq34e => self.mr,
            Eq34f | Eq34g | Eq34k => self.s0,
            Eq34h | Eq34i | Eq34j => self.s1,
            Eq7 => self.nz - self.nx,
            XBar => self.nx,
        }
    }

    /// First column of block `u`.
    pub fn col(&self, u: Unknown) -> usize {
        UNKNOWNS.iter().take_while(|&&x| x != u).map(|&x| self.size_of(x)).sum()
    }

    /// First row of block `e`.
    pub fn row(&self, e: Equation) -> usize {
        EQUATIONS.iter().take_while(|&&x| x != e).map(|&x| self.rows_of(x)).sum()
    }

    /// Column of unknown `i` of block `u`.
    #[inline]
    pub fn at(&self, u: Unknown, i: usize) -> usize {
        debug_assert!(i < self.size_of(u), "{u:?}[{i}] of {}", self.size_of(u));
        self.col(u) + i
    }

    /// Row of equation `i` of block `e`.
    #[inline]
    pub fn row_at(&self, e: Equation, i: usize) -> usize {
        debug_assert!(i < self.rows_of(e), "{e:?}[{i}] of {}", self.rows_of(e));
        self.row(e) + i
    }

    /// Number of states (S, W, X): the columns of A.
    pub fn ns(&self) -> usize {
        self.s0 + self.s1 + self.nx
    }

    /// Dimension of the (square) system.
    pub fn dim(&self) -> usize {
        let cols: usize = UNKNOWNS.iter().map(|&u| self.size_of(u)).sum();
        debug_assert_eq!(cols, EQUATIONS.iter().map(|&e| self.rows_of(e)).sum::<usize>());
        cols
    }

    /// Whether the states complete the constraints to the coordinates (square system):
    /// s0 + mr = n and s1 + mn = s0.
    pub fn is_square(&self) -> bool {
        self.s0 + self.mr == self.n && self.s1 + self.mn == self.s0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The offsets of the blocks, written out once by hand from Table 1 (with the
    /// generalization above): the layout computed from the block sizes agrees.
    #[test]
    fn offsets_follow_table_1() {
        let l = Eq34 { n: 12, m: 8, mr: 7, mn: 2, s0: 5, s1: 3, nx: 1, nz: 4 };
        assert!(l.is_square());
        let (n, m, mr, mn, s0, s1) = (12, 8, 7, 2, 5, 3);
        assert_eq!(l.col(Unknown::QDot), n);
        assert_eq!(l.col(Unknown::SDot), 2 * n + s1);
        assert_eq!(l.col(Unknown::Nu), 2 * n + s1 + s0 + m);
        assert_eq!(l.col(Unknown::Z), 4 * n + 2 * s1 + 2 * s0 + m + mn);
        let f = 2 * n + m + mn + 2 * mr + mn;
        assert_eq!(l.row(Equation::Eq34d), 2 * n + m + mn);
        assert_eq!(l.row(Equation::Eq34f), f);
        assert_eq!(l.row(Equation::Eq34k), f + 2 * s0 + 3 * s1);
        assert_eq!(l.row(Equation::XBar), f + 3 * s0 + 3 * s1 + 4 - 1);
        assert_eq!(l.dim(), l.col(Unknown::Z) + 4);
        assert_eq!(l.dim(), l.row(Equation::XBar) + 1);
    }
}
