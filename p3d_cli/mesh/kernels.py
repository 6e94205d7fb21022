"""The compiled kernels, when they are built: ``p3d_cli.mesh._kernels`` (C, optional).

``pip install`` compiles ``_kernels.c`` when a C compiler is there and skips it otherwise; every
caller then runs the numpy code it replaces, which gives the same results bit for bit (the
kernels replay the same IEEE operations in the same order, numpy's pairwise sums included:
docs/performance.md, "The compiled kernels"). ``P3D_PURE_NUMPY=1`` in the environment switches
them off, for comparisons and for the tests of the numpy code.
"""

from __future__ import annotations

import os
from types import ModuleType

import numpy as np

from p3d_cli.mesh.splitmix import mix


def _load() -> ModuleType | None:
    if os.environ.get("P3D_PURE_NUMPY", "") not in ("", "0"):
        return None
    try:
        from p3d_cli.mesh import _kernels  # type: ignore[attr-defined]  # the built extension
    except ImportError:
        return None
    return _kernels


#: The compiled module, or None (not built, or switched off). Tests set it to None to run the
#: numpy code in process.
KERNELS: ModuleType | None = _load()


def compiled() -> ModuleType | None:
    """The compiled kernels, or None when p3d runs on numpy alone."""
    return KERNELS


def takes(block) -> bool:
    """Whether the kernels read ``block`` as it is: a ``(k, 3, 3)`` numpy array of native
    float32 or float64 (any strides, such as a binary STL's 50-byte records)."""
    return (isinstance(block, np.ndarray) and block.ndim == 3 and block.shape[1:] == (3, 3)
            and block.dtype.isnative and block.dtype in (np.float32, np.float64))


def sort(keys: np.ndarray) -> None:
    """Sort a contiguous uint64 array in place: the compiled radix sort when there is one (its
    time per key stays flat with size; numpy's grows), else ``ndarray.sort``. Same result."""
    kernels = KERNELS
    if kernels is not None and keys.dtype == np.uint64 and keys.flags.c_contiguous and keys.flags.writeable:
        kernels.sort(keys)
    else:
        keys.sort()


def key_buffer(count: int) -> np.ndarray:
    """An uninitialised ``(count,)`` uint64 array for edge keys, in ordinary pages.

    numpy asks the kernel for transparent huge pages for large arrays, and where the kernel
    compacts memory to find them (``defrag`` = ``madvise``, common in VMs) a 24 MB array took
    0.05-0.2 s of system time to appear, more than filling it (measured for issue 32). So the
    keys are allocated with that request off: from the C heap, where they reuse memory a
    reader has freed (a binary PLY's), or, past glibc's mmap threshold, in fresh pages whose
    untouched parts (the buckets' slack) take no memory.
    """
    try:
        from numpy._core.multiarray import _set_madvise_hugepage  # type: ignore[attr-defined]
    except ImportError:                     # numpy < 2, or a build without the switch
        return np.empty(count, dtype=np.uint64)
    before = _set_madvise_hugepage(False)
    try:
        return np.empty(count, dtype=np.uint64)
    finally:
        _set_madvise_hugepage(before)


def key_balance(keys: np.ndarray) -> int:
    """The balance of side keys: ``g = mix(key | 1)`` summed over the forward keys (bit 0 set)
    less over the others, mod 2**64 (``ForwardBuckets``; ``forward_block`` sums the same)."""
    g = mix(keys | np.uint64(1))
    forward = (keys & np.uint64(1)).astype(bool)
    return (int(g[forward].sum(dtype=np.uint64)) - int(g[~forward].sum(dtype=np.uint64))) % (1 << 64)


def print_buffer(count: int) -> np.ndarray:
    """An uninitialised ``(count,)`` uint32 array, in ordinary pages (``key_buffer``)."""
    return key_buffer((count + 1) // 2).view(np.uint32)[:count]


class Buckets:
    """Edge keys dealt by the compiled pass to buckets of their top bits as they are made, so
    that sorting them needs no pass over all of them (a bucket is sorted in cache, then moved
    down beside the one before: ``sorted_keys``).

    A bucket holds ``cap`` keys: the mean plus eight standard deviations of the count a bucket
    gets when the keys are hashes (the two sides of an edge share a bucket, so the count is
    twice a Poisson count of edges). Pages never written take no memory (``key_buffer``): the
    slack costs address space, not resident memory. A mesh whose keys crowd
    one bucket (the same edge thousands of times) overflows it: ``overflow`` is then set and
    the caller makes the keys again, one after the other.
    """

    #: Keys per bucket on average: a bucket and the sort's buffer of its size stay in a 1 MB
    #: L2 cache.
    MEAN = 1 << 15

    def __init__(self, count: int) -> None:
        import math

        # 2**k buckets by the top k bits (at least two: the sort takes the bits below them).
        bits = max(1, (count // self.MEAN).bit_length() - 1)
        self.shift = 64 - bits
        buckets = 1 << bits
        mean = count / buckets
        self.cap = int(math.ceil(mean + 8 * math.sqrt(2 * mean) + 64))
        self.cap += self.cap % 2            # even: a bucket of 4-byte prints is whole 8-byte words
        self.keys = key_buffer(buckets * self.cap)
        self.fill = np.zeros(buckets, dtype=np.int64)
        self.overflow = False

    @classmethod
    def like(cls, other: Buckets) -> Buckets:
        """Empty buckets of ``other``'s shift and room: the keys that go with ``other``'s, for
        a scan of both bucket by bucket (``split_groups``)."""
        buckets = cls.__new__(cls)
        buckets.shift, buckets.cap = other.shift, other.cap
        buckets.keys = key_buffer(other.keys.size)
        buckets.fill = np.zeros_like(other.fill)
        buckets.overflow = False
        return buckets

    def populate(self, count: int) -> None:
        """Make the pages of the slots that every bucket fills with ``count`` hashed keys (the
        mean less eight standard deviations, as ``cap`` adds them) in one call a bucket, not
        one page fault a page: no more memory, less system time (Linux; nothing elsewhere)."""
        kernels = KERNELS
        if kernels is not None:
            kernels.populate(self.keys, self.fill, self.cap, self.shift, self._sure(count))

    def _sure(self, count: int) -> int:
        """The slots every bucket fills with ``count`` hashed keys: the mean less eight
        standard deviations, as ``cap`` adds them."""
        import math

        mean = count / self.fill.size
        return max(0, int(mean - 8 * math.sqrt(2 * mean)))

    def add(self, block_keys: np.ndarray) -> None:
        """Deal keys made by the numpy code (a block the compiled pass left to it)."""
        bucket = (block_keys >> np.uint64(self.shift)).astype(np.int64)
        counts = np.bincount(bucket, minlength=self.fill.size)
        if (self.fill + counts > self.cap).any():
            self.overflow = True
            return
        order = np.argsort(bucket, kind="stable")
        bucket = bucket[order]
        rank = np.arange(bucket.size) - (np.cumsum(counts) - counts)[bucket]
        self.keys[bucket * self.cap + self.fill[bucket] + rank] = block_keys[order]
        self.fill += counts

    def sorted_keys(self) -> np.ndarray:
        """All the keys, sorted (a view of the start of the buffer)."""
        kernels = KERNELS
        assert kernels is not None and not self.overflow  # noqa: S101 - made only with the kernels
        return self.keys[:kernels.finish(self.keys, self.fill, self.cap, self.shift)]


class ForwardBuckets(Buckets):
    """The closed test of ``p3d props`` on half the keys (issue 32): the compiled pass
    (``forward_block``) deals to buckets only the keys of the sides that run from the smaller
    corner hash to the larger (bit 0 set), and sums ``g = mix(key | 1)`` over those minus
    ``g`` over the others (``balance``, mod 2**64) and counts the others (``backward``); of the
    others it keeps 32 bits each, the *prints* (the key's bits below its bucket's), in buckets
    of their own, for the open road.

    The keys pair up (``p3d_cli.mesh.closed.keys_pair_up``: every edge once each way) exactly
    when no kept key is there twice, the two directions are equally many and the balance is
    zero (``closed``): with no forward key twice, an edge used otherwise than once each way is
    used unequally often in the two directions, and adds ``g(edge)`` times that nonzero
    difference to the balance, which the other such edges cancel only by a 64-bit coincidence
    (as two edges' keys must coincide to fool the sort). ``closed`` False says nothing more:
    the caller then groups these keys with the prints (``print_groups``) and picks the sides
    of the groups found unbalanced in one more pass; where that proves nothing, it deals the
    other half of the keys beside these (``Buckets.like``, the kernel's ``backward_block``) and
    scans the two together (``split_groups``; ``p3d_cli.mesh.analysis``).
    """

    #: The prints are kept where the keys take at most this many buckets (meshes up to about
    #: 1.4M faces). Every closed mesh pays for them (the stores, and fresh pages: 4 bytes a
    #: backward side): about 1 % of ``p3d props``' CPU time at 1M faces and 32 buckets, but
    #: 10 % at 4M faces (128 buckets) and 13 % at 16M (512: twice as many places written at
    #: once, 96 MB more pages), more than the pass they spare an open mesh is worth there.
    PRINT_BUCKETS = 32

    def __init__(self, sides: int) -> None:
        super().__init__((sides + 1) // 2)      # the count of a bucket: a Poisson count of keys
        self.balance = 0
        self.backward = 0
        self.populate((sides + 1) // 2)
        #: The backward sides' prints (``forward_block``): the 32 bits of each key below its
        #: bucket's bits, dealt to buckets of the same shift and room (4 bytes a side, not 8),
        #: for the open road (``p3d_cli.mesh.analysis``). ``whole`` says they are all there:
        #: false for meshes with more than ``PRINT_BUCKETS`` buckets (none are kept), and
        #: cleared when one was lost (a full bucket, or a block the numpy code took).
        self.whole = self.fill.size <= self.PRINT_BUCKETS
        self.prints = print_buffer(self.keys.size if self.whole else 0)
        self.print_fill = np.zeros_like(self.fill)
        if KERNELS is not None and self.whole:
            # The prints' pages too: a bucket of ``cap`` prints is ``cap / 2`` words of the
            # buffer under them (``cap`` is even).
            KERNELS.populate(self.prints.base, self.fill, self.cap // 2, self.shift, self._sure(sides // 2) // 2)

    def add(self, block_keys: np.ndarray) -> None:
        """Deal the forward keys of a block the compiled pass left to the numpy code, and add
        its sides to the balance."""
        forward = (block_keys & np.uint64(1)).astype(bool)
        self.balance = (self.balance + key_balance(block_keys)) % (1 << 64)
        self.backward += int(block_keys.size - forward.sum())
        self.whole = False                  # its backward sides' prints are not dealt
        super().add(block_keys[forward])

    def closed(self) -> bool:
        """Whether all the sides' keys pair up (see the class)."""
        kernels = KERNELS
        assert kernels is not None and not self.overflow  # noqa: S101 - made only with the kernels
        forward = int(self.fill.sum())
        return (forward > 0 and forward == self.backward and self.balance == 0
                and bool(kernels.distinct(self.keys, self.fill, self.cap, self.shift)))


class NotTaken(Exception):
    """A block the kernels do not read as it is (another dtype or byte order)."""


def confirm_fans(blocks, fan: np.ndarray, count: int, is_first: np.ndarray, volume=None):
    """``p3d_cli.mesh.paired._confirm`` by the compiled kernels (the same comparisons, block by
    block): the fans' coordinates ``(count, 3)`` as stored, or None when some corner differs
    from its fan's first corner. Raises ``NotTaken`` for a block the kernels do not read.

    With ``volume`` (a ``SignedVolume``), each block's volume sums are added to it as well, with
    the bits its ``add_columns`` gives."""
    fast = KERNELS
    assert fast is not None  # noqa: S101 - called only with the kernels
    axes = np.zeros((3, count))
    dtype = None
    done = 0
    for block in blocks():
        block = np.asarray(block)
        k = len(block)
        if k == 0:
            continue
        if not takes(block):
            raise NotTaken                          # the numpy code compares in the stored dtype
        if dtype is None:
            dtype = block.dtype
        if not fast.confirm(block, fan[3 * done:3 * (done + k)], is_first[3 * done:3 * (done + k)].view(np.uint8),
                            axes):
            return None                             # colliding keys paired two edges
        if volume is not None:
            _, _, totals, magnitude, _, _ = fast.block(block, *volume.origin, None, 0)
            volume.add_sums(totals[0], magnitude, k)
        done += k
    if dtype is None:
        return np.zeros((count, 3))
    # The coordinates as stored (float32 values are exact in float64 and back).
    return np.ascontiguousarray(axes.T).astype(dtype, copy=False)
