//! Typed indices: a vertex, face, half-edge or edge is never a bare integer in the public API.

macro_rules! define_id {
    ($(#[$doc:meta])* $name:ident, $prefix:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
        pub struct $name(u32);

        impl $name {
            /// Wraps a raw 0-based index.
            #[inline]
            pub const fn new(raw: u32) -> Self {
                Self(raw)
            }

            /// Wraps a `usize` index, or `None` when it does not fit the 32-bit id space.
            #[inline]
            pub fn from_usize(index: usize) -> Option<Self> {
                u32::try_from(index).ok().map(Self)
            }

            /// The raw 0-based index.
            #[inline]
            pub const fn raw(self) -> u32 {
                self.0
            }

            /// The index as `usize`, for indexing caller-side arrays.
            #[inline]
            pub const fn index(self) -> usize {
                self.0 as usize
            }
        }

        impl std::fmt::Debug for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, concat!($prefix, "{}"), self.0)
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, concat!($prefix, " {}"), self.0)
            }
        }
    };
}

define_id!(
    /// A vertex of a mesh or polygon soup (0-based, in input order).
    VertexId,
    "vertex"
);
define_id!(
    /// A face of a mesh or polygon soup (0-based, in input order).
    FaceId,
    "face"
);
define_id!(
    /// A half-edge: one corner of one face, directed from that corner's vertex to the next one.
    ///
    /// Half-edges of face `f` are numbered contiguously in the face's vertex order, so the
    /// half-edge ids of a mesh are the positions of the corners in the flattened face list.
    HalfEdgeId,
    "half-edge"
);
define_id!(
    /// An undirected edge: a pair of twin half-edges, or one half-edge on a boundary.
    EdgeId,
    "edge"
);
