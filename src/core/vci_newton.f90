!> Damped Newton iteration on LAPACK for small dense systems R(x) = 0.
!>
!> Convergence is judged row by row against the size of the terms that make up each row
!> (|r_i| <= atol + rtol * scale_i), because the sub-steps of an impact can be arbitrarily short
!> and residuals then scale like 1/step. The linear solve is an LU factorisation (dgetrf/dgetrs)
!> of the row-equilibrated Jacobian; when
!> that matrix is singular, a rank-revealing least-squares solve (dgelsd) gives the minimum-norm
!> step instead. All workspace is allocated by `reserve`, so `solve` allocates nothing.
!>
!> Nothing non-finite reaches LAPACK: a residual, scale or Jacobian with NaN/Inf (a callback's
!> huge but finite values overflow in differences) ends the solve with VCI_ERR_NONFINITE, or, at a
!> trial point of the line search, is backed off from like a failed evaluation. (With NaN input,
!> OpenBLAS's dgelsd can loop forever and reference LAPACK's prints through XERBLA.)
module vci_newton
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp, i8
  use vci_status, only: VCI_OK, VCI_ERR_NEWTON, VCI_ERR_NONFINITE, VCI_ERR_MEMORY, VCI_ERR_ARGUMENT
  use vci_lapack, only: dgetrf, dgetrs, dgelsd
  use vci_kernels, only: equilibrate, scaled_merit, small_lu, small_lu_solve, pivots_regular
  use vci_banded, only: vci_banded_lu_t, outside_band
  use vci_banded_matrix, only: vci_band_matrix_t
  use vci_sparse_matrix, only: vci_sparse_matrix_t
  use vci_sparse, only: vci_sparse_lu_t, vci_sparse_pattern_t, outside_pattern, pattern_rows
  use vci_factor, only: vci_dense_lu_t
  use vci_bordered, only: vci_bordered_t
  implicit none
  private

  interface all_finite
    module procedure all_finite_1, all_finite_2
  end interface all_finite

  !> Why a solve stopped.
  integer, parameter, public :: NEWTON_CONVERGED = 0
  integer, parameter, public :: NEWTON_MAX_ITERATIONS = 1  !< iteration cap reached
  integer, parameter, public :: NEWTON_NO_DESCENT = 2      !< backtracking found no decrease
  integer, parameter, public :: NEWTON_SINGULAR = 3        !< even the least-squares solve failed
  integer, parameter, public :: NEWTON_EVALUATION = 4      !< the residual or Jacobian reported failure
  integer, parameter, public :: NEWTON_NONFINITE = 5       !< residual, scale or Jacobian not finite (overflow)
  integer, parameter, public :: NEWTON_STRUCTURE = 6       !< a nonzero outside the declared band (debug check)
  integer, parameter, public :: NEWTON_MEMORY = 7          !< no memory for the dense matrices a system needed

  !> A starting merit at or below this is round-off: the start is accepted without a Newton step.
  real(dp), parameter, public :: start_roundoff = 1.0e-3_dp

  !> Systems of at least this many unknowns are "large": they reuse the Newton matrix's factors across
  !> iterations and solves (simplified Newton, below) and schemes size their rows in O(n) per residual.
  integer, parameter, public :: vci_large_system = 16

  !> Which factors a Newton direction used (lu_solve solves with the same): the whole matrix's dense
  !> LU (lu, ipiv), or one of the vci_factor_t kinds, or a block of those bordered (vci_bordered).
  integer, parameter :: FACTORS_WHOLE = 0, FACTORS_BAND = 1, FACTORS_SPARSE = 2, FACTORS_BLOCK = 3, &
                        FACTORS_BORDERED = 4

  !> A nonlinear system as Newton sees it. A residual that fails (stat /= 0) at a trial point of
  !> the line search is backed off from, unless the system sets `unrecoverable` (a callback's
  !> negative return): then the solve ends at once with that status.
  type, abstract, public :: vci_system_t
    logical :: unrecoverable = .false.  !< set by the residual: its failure ends the solve at once
  contains
    !> r = R(x) and the size of each row's terms (interface residual_iface).
    procedure(residual_iface), deferred :: residual
    !> jac = dR/dx (interface jacobian_iface).
    procedure(jacobian_iface), deferred :: jacobian
    !> May the line search try x? (default: always)
    procedure :: admissible => always_admissible
    !> A nonzero key names a family of systems whose Jacobians may share LU factors (default 0: none).
    procedure :: reuse_key => never_reuse
    !> Chord steps on the kept factors of another key of the family: their scale (default 0: none).
    procedure :: chord_ratio => no_chord_ratio
    !> The family key of a bordered system's block at its solution x (default 0: not kept).
    procedure :: block_key => no_block_key
    !> The Jacobian's structure: a banded leading block and a dense border (default: dense).
    procedure :: structure => no_structure
    !> A declared sparse pattern of the leading block instead (default: none; vci_sparse).
    procedure :: sparse_structure => no_sparse_structure
    !> Unknowns at the end that border the rest (1: an impact stage's alpha or mu; default 0).
    procedure :: border => no_border
    !> Does the posed system write its Jacobian in its declared band (band_jacobian)? (default: no)
    procedure :: packs_band => never_packs
    !> jac = dR/dx written in the declared structure (vci_band_matrix_t, no n x n array).
    procedure :: band_jacobian => no_band_jacobian
    !> Does the posed system write its Jacobian in its declared sparse pattern? (default: no)
    procedure :: packs_sparse => never_packs
    !> jac = dR/dx written in the declared pattern (vci_sparse_matrix_t, no n x n array).
    procedure :: sparse_jacobian => no_sparse_jacobian
  end type vci_system_t

  abstract interface
    !> r = R(x); scale(i) = size of the terms summed in row i; stat /= 0 on failure.
    subroutine residual_iface(self, x, r, scale, stat)
      import :: vci_system_t, dp
      class(vci_system_t), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: r(:), scale(:)
      integer, intent(out) :: stat
    end subroutine residual_iface
    !> jac = dR/dx at x (r is R(x), already evaluated, for difference quotients).
    subroutine jacobian_iface(self, x, r, jac, stat)
      import :: vci_system_t, dp
      class(vci_system_t), intent(inout) :: self
      real(dp), intent(in) :: x(:), r(:)
      real(dp), intent(out) :: jac(:, :)
      integer, intent(out) :: stat
    end subroutine jacobian_iface
  end interface

  !> Outcome of one solve.
  type, public :: vci_newton_result_t
    integer :: status = VCI_OK         !< VCI_OK, VCI_ERR_NEWTON, or the evaluation's own status
    integer :: reason = NEWTON_CONVERGED  !< NEWTON_CONVERGED or why not (NEWTON_*)
    integer :: iterations = 0          !< Jacobian evaluations + polishing step
    logical :: used_fallback = .false. !< the least-squares solve was needed
    real(dp) :: scaled_residual = 0.0_dp  !< max_i |r_i| / (atol + rtol scale_i) at the end
    integer :: bad_row = 0                !< NEWTON_STRUCTURE: the row of the entry outside the declared band
    integer :: bad_col = 0                !< NEWTON_STRUCTURE: its column
    logical :: damped = .false.           !< (issue 27) the line search shortened a full Newton step
  end type vci_newton_result_t

  !> Damped Newton's method on LAPACK: solves a vci_system_t; settings, workspace and counters.
  type, public :: vci_newton_t
    real(dp) :: atol = 0.0_dp          !< absolute floor of the per-row tolerance
    real(dp) :: rtol = 1.0e-12_dp      !< tolerance relative to the size of each row's terms
    integer :: max_iterations = 30     !< Jacobian evaluations per solve
    integer :: max_backtracks = 12     !< halvings of the step in the line search
    logical :: polish = .true.         !< one extra step with the last factorisation: ~ machine precision
    !> Systems of at most this many unknowns are factorised by the in-line LU below (partial
    !> pivoting, the same elimination as LAPACK's unblocked dgetf2) instead of dgetrf/dgetrs: for a
    !> 3x3 matrix a LAPACK call through OpenBLAS costs ~10x its arithmetic (locks, dispatch), and at
    !> 9x9 (Lobatto s = 3 with a constraint) dgetrf alone took 8k instructions. Every system below
    !> vci_large_system takes it. 0: always LAPACK. docs/bench/throughput.md measures the difference;
    !> test_newton compares both paths.
    integer :: small_lu_max = vci_large_system - 1
    !> Simplified Newton for systems of at least reuse_min unknowns: a solve whose system has the
    !> same nonzero reuse_key as the one the factors were computed for starts with chord steps on
    !> those factors, and evaluates and factorises a new Jacobian only when a chord step contracts
    !> the scaled residual by less than reuse_contraction (or fails). Huge(1): never.
    integer :: reuse_min = vci_large_system
    real(dp) :: reuse_contraction = 0.25_dp  !< a chord step must contract the scaled residual by this
    !> After a full Newton step that left the scaled residual above the tolerance, try one chord step
    !> on the same factors before a new Jacobian (accepted when it reaches the tolerance or contracts
    !> by reuse_contraction). Near the solution the first step's error is ~ the square of the start's,
    !> so the chord step finishes where a second Jacobian and factorisation would (issue 25: Lobatto
    !> with constraints, docs/bench/lobatto.md). Off by default; the stepper sets it per scheme.
    logical :: chord_after_newton = .false.
    !> The polish only when the converged residual is above this many units of round-off of its
    !> terms (phi rtol > polish_above eps; 0: always): a residual within a few ulps gains nothing
    !> from it, and a rejected polish leaves the scheme's cached node values stale (issue 25:
    !> Lobatto with constraints at rtol 1e-14, docs/bench/lobatto.md). The stepper sets it per scheme.
    real(dp) :: polish_above = 0.0_dp
    integer(i8) :: factorisations = 0     !< LU factorisations of Newton matrices so far
    logical, private :: have_lu = .false.
    integer, private :: lu_n = 0
    real(dp), private :: lu_key = 0.0_dp
    integer :: capacity = 0               !< unknowns the workspace is sized for (reserve)
    real(dp), allocatable, private :: jac(:, :), lu(:, :), r(:), sc(:), dx(:), xt(:), rt(:), sct(:)
    real(dp), allocatable, private :: sv(:), work(:), rw(:), brw(:), bvec(:)
    !> Unknowns the dense matrices (jac, lu) and the least-squares workspace are sized for: reserve's
    !> dense_max, grown on demand (a dense fallback of a structured system) — with a declared band
    !> Newton's matrix lives in bmat and these stay small (issue 28 item 3)
    integer :: dense_capacity = 0
    !> Newton's matrix in its declared band (vci_banded_matrix) when the system writes it there
    type(vci_band_matrix_t), private :: bmat
    logical, private :: packed = .false.           !< this solve's Jacobian is in bmat
    !> Newton's matrix in its declared sparse pattern (vci_sparse_matrix) when the system writes it there
    type(vci_sparse_matrix_t), private :: smat
    logical, private :: spacked = .false.          !< this solve's Jacobian is in smat
    integer, allocatable, private :: ipiv(:), iwork(:)
    !> Factorisations in a declared structure (band or sparse pattern, with their dense border)
    integer(i8) :: structured_factorisations = 0
    !> The factors of the structured kinds (vci_factor_t): a band with a Schur-complement border,
    !> the posed system's or its bordered block's (vci_banded) ...
    type(vci_banded_lu_t), private :: band
    !> ... a sparse LU of a declared pattern (vci_sparse, KLU) ...
    type(vci_sparse_lu_t), private :: sparse
    !> ... and a dense block's LU (a bordered system that declares no structure)
    type(vci_dense_lu_t), private :: blockd
    integer, private :: fkind = FACTORS_WHOLE      !< the factors the last direction used (FACTORS_*)
    integer, private :: snb = 0, sbw = -1          !< the posed system's band block and half-bandwidth
    logical, private :: scheck = .false.           !< check the structure on every Newton matrix
    integer, private :: ssp = 0                    !< the posed system's sparse block (0: none)
    type(vci_sparse_pattern_t), pointer, private :: spat => null()
    !> Systems that declare a border of one unknown (an impact's stage 1 and 2): the block is
    !> factorised alone, in its own structure (dense, band or sparse), and the border eliminated by
    !> its Schur complement (vci_bordered). False: the whole matrix is factorised (the comparison
    !> path of the tests and benchmarks).
    logical :: bordered = .true.
    !> ... for systems of at least this many unknowns: below, the in-line LU of the whole matrix costs
    !> less than the block's plus the elimination (ellipse, walled pendulum: docs/bench/bordered.md).
    integer :: border_min = vci_large_system
    !> Systems of more than reuse_min unknowns with a dense block keep the block's factors across the
    !> iterations of one bordered solve (a chord on the block; the border is the current Jacobian's)
    !> while each step contracts the scaled residual by reuse_contraction; false: refactorise it at
    !> every iteration (as band and sparse blocks always are: their factorisation is O(n)).
    logical :: border_chord = .true.
    integer(i8) :: bordered_directions = 0         !< Newton directions by bordering
    type(vci_bordered_t), private :: bord          !< the current border of the block
    integer, private :: bkind = FACTORS_BLOCK      !< the block's factors (FACTORS_BAND/SPARSE/BLOCK)
    integer, private :: block_ni = 0               !< the block's unknowns
    logical, private :: block_stale = .true.       !< refactorise the bordered block at the next direction
    integer, private :: nbord = 0                  !< the posed system's border (0 or 1)
    logical, private :: block_reused = .false.     !< the last bordered direction used an earlier block
    !> Chord directions on the kept factors are scaled by this: 1 for the key they were made for,
    !> sys%chord_ratio for another key of the family (issue 28: sub-steps of other lengths)
    real(dp), private :: lu_ratio = 1.0_dp
  contains
    !> Allocate workspace for systems of up to nmax unknowns (call once, outside the step loop).
    procedure :: reserve
    !> Drop the kept factors: the next solve starts with a new Jacobian (a fresh run's start).
    procedure :: forget_factors
    !> The kept factors, for a checkpoint (restart bit for bit).
    procedure :: kept_factors
    !> Take factors from a checkpoint: the next solve of their family starts with chord steps on them.
    procedure :: keep_factors
    !> Solve sys%residual(x) = 0 for x(1:n), starting from the given x.
    procedure :: solve
    !> Solve the small dense system a x = b in place (b becomes x), with the solver's workspace.
    procedure :: linear_solve
    !> Solve J x = b for the Jacobian J of a system at x, assembled in its declared structure.
    procedure :: jacobian_solve
    !> After a solve that failed on convergence: the row with the largest scaled residual.
    procedure :: worst_row
  end type vci_newton_t

contains

  !> A nonzero key names a family of systems whose Jacobians are close enough to share factors
  !> (e.g. regular sub-steps of one length and direction); 0: never reuse.
  real(dp) function never_reuse(self)
    class(vci_system_t), intent(inout) :: self
    never_reuse = 0.0_dp
  end function never_reuse

  !> The factor by which a chord direction from factors kept for key old_key is scaled to serve
  !> this system (whose reuse_key differs); 0: those factors are not used. Default: never.
  real(dp) function no_chord_ratio(self, old_key)
    class(vci_system_t), intent(inout) :: self
    real(dp), intent(in) :: old_key
    no_chord_ratio = 0.0_dp
  end function no_chord_ratio

  !> A bordered system's block is the Newton matrix of another system (an impact stage's block is a
  !> sub-step's): the reuse_key of that family at the solution x, under which the block's factors
  !> are kept for it; 0: they are not. Default: never.
  real(dp) function no_block_key(self, x)
    class(vci_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    no_block_key = 0.0_dp
  end function no_block_key

  !> The Jacobian's structure: unknowns 1..nb form a block whose entries vanish outside |i - j| <= bw,
  !> the others a dense border; check: verify the band on every matrix. nb = 0 or bw < 0: dense.
  subroutine no_structure(self, nb, bw, check)
    class(vci_system_t), intent(inout) :: self
    integer, intent(out) :: nb, bw
    logical, intent(out) :: check
    nb = 0; bw = -1; check = .false.
  end subroutine no_structure

  !> A declared sparse pattern of the leading block: unknowns 1..nb with the pattern pat (a pointer
  !> into the model), the others a dense border; check: verify the pattern on every matrix.
  !> pat null or nb = 0: none (the default).
  subroutine no_sparse_structure(self, nb, pat, check)
    class(vci_system_t), intent(inout) :: self
    integer, intent(out) :: nb
    type(vci_sparse_pattern_t), pointer, intent(out) :: pat
    logical, intent(out) :: check
    nb = 0; pat => null(); check = .false.
  end subroutine no_sparse_structure

  !> Does the posed system write its Jacobian in its declared band? Not unless it says so.
  logical function never_packs(self)
    class(vci_system_t), intent(inout) :: self
    never_packs = .false.
  end function never_packs

  !> Not called unless packs_band says so: a system that packs its band overrides it.
  subroutine no_band_jacobian(self, x, r, mat, stat)
    class(vci_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), r(:)
    type(vci_band_matrix_t), intent(inout) :: mat
    integer, intent(out) :: stat
    stat = VCI_ERR_ARGUMENT
  end subroutine no_band_jacobian

  !> Not called unless packs_sparse says so: a system that packs its pattern overrides it.
  subroutine no_sparse_jacobian(self, x, r, mat, stat)
    class(vci_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), r(:)
    type(vci_sparse_matrix_t), intent(inout) :: mat
    integer, intent(out) :: stat
    stat = VCI_ERR_ARGUMENT
  end subroutine no_sparse_jacobian

  !> Unknowns at the end of x that border the rest: none unless the system says so.
  integer function no_border(self)
    class(vci_system_t), intent(inout) :: self
    no_border = 0
  end function no_border

  logical function always_admissible(self, x)
    class(vci_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    always_admissible = .true.
  end function always_admissible

  !> Allocate workspace for systems of up to nmax unknowns (call once, outside the step loop).
  !> dense_max (optional, default nmax): the largest system without a declared band the caller
  !> poses — the dense matrices are sized for it (a band model's n x n never exists; a dense
  !> fallback grows them on demand). stat (optional): VCI_ERR_MEMORY when an allocation fails (the
  !> solver then has no workspace).
  subroutine reserve(self, nmax, stat, dense_max)
    class(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: nmax
    integer, intent(out), optional :: stat
    integer, intent(in), optional :: dense_max
    integer :: st, dm
    if (present(stat)) stat = VCI_OK
    dm = nmax
    if (present(dense_max)) dm = max(1, min(nmax, dense_max))
    if (self%capacity >= nmax .and. self%dense_capacity >= dm) return
    call release(self)
    allocate (self%r(nmax), self%sc(nmax), self%dx(nmax), &
              self%xt(nmax), self%rt(nmax), self%sct(nmax), self%sv(nmax), self%ipiv(nmax), self%rw(nmax), &
              self%brw(nmax), self%bvec(nmax), stat=st)
    if (st == 0) call grow_dense(self, dm, st)
    if (st /= 0) then
      call release(self)       ! a multi-object allocate may fail part-way: free what it got
      if (present(stat)) stat = VCI_ERR_MEMORY
      return
    end if
    self%capacity = nmax
  end subroutine reserve

  !> Dense matrices (jac, lu) and the least-squares workspace for systems of n unknowns (kept when
  !> large enough; growing them drops kept dense factors). st /= 0: out of memory (none left).
  subroutine grow_dense(self, n, st)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    integer, intent(out) :: st
    real(dp) :: query(1), a(1, 1), b(1, 1), s(1)
    integer :: iq(1), rank, info, lwork, liwork, nlvl
    st = 0
    if (self%dense_capacity >= n) return
    if (self%fkind == FACTORS_WHOLE) self%have_lu = .false.
    call release_dense(self)
    allocate (self%jac(n, n), self%lu(n, n), stat=st)
    if (st == 0) then
      call dgelsd(n, n, 1, a, n, b, n, s, -1.0_dp, rank, query, -1, iq, info)
      lwork = max(1, int(query(1)))
      nlvl = max(0, int(log(real(n, dp) / 26.0_dp) / log(2.0_dp)) + 1)
      liwork = max(1, 3 * n * nlvl + 11 * n, iq(1))
      allocate (self%work(lwork), self%iwork(liwork), stat=st)
    end if
    if (st /= 0) then
      call release_dense(self); return
    end if
    self%dense_capacity = n
  end subroutine grow_dense

  !> No dense matrices (each array freed on its own).
  subroutine release_dense(self)
    type(vci_newton_t), intent(inout) :: self
    if (allocated(self%jac)) deallocate (self%jac)
    if (allocated(self%lu)) deallocate (self%lu)
    if (allocated(self%work)) deallocate (self%work)
    if (allocated(self%iwork)) deallocate (self%iwork)
    self%dense_capacity = 0
  end subroutine release_dense

  !> Drop the factors kept for simplified Newton: the next solve of a large system starts with a
  !> new Jacobian, as the first solve after reserve does. The driver calls it at the points a run
  !> may be continued from (docs/DESIGN.md, "Restart bit for bit"), so that a run continued there
  !> and one that went through it solve the same systems from the same factors.
  subroutine forget_factors(self)
    class(vci_newton_t), intent(inout) :: self
    self%have_lu = .false.
  end subroutine forget_factors

  !> The factors kept for simplified Newton, for a checkpoint: nf unknowns (0: none kept), the
  !> family's key, the row weights and the LU factors with their pivots (copies; stat /= 0 when
  !> they cannot be allocated, then nf = 0).
  subroutine kept_factors(self, nf, key, rw, lu, ipiv, stat)
    class(vci_newton_t), intent(in) :: self
    integer, intent(out) :: nf
    real(dp), intent(out) :: key
    real(dp), allocatable, intent(out) :: rw(:), lu(:, :)
    integer, allocatable, intent(out) :: ipiv(:)
    integer, intent(out) :: stat
    nf = 0; key = 0.0_dp; stat = VCI_OK
    if (.not. self%have_lu .or. self%fkind /= FACTORS_WHOLE) return   ! (structured factors: the continued run refactorises)
    allocate (rw(self%lu_n), lu(self%lu_n, self%lu_n), ipiv(self%lu_n), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    nf = self%lu_n; key = self%lu_key
    rw = self%rw(1:nf); lu = self%lu(1:nf, 1:nf); ipiv = self%ipiv(1:nf)
  end subroutine kept_factors

  !> Take factors from a checkpoint (kept_factors of the same system sizes): the next solve of
  !> the family `key` starts with chord steps on them, as the run that wrote them would have.
  !> Ignored (no factors kept) when they do not fit the workspace.
  subroutine keep_factors(self, nf, key, rw, lu, ipiv)
    class(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: nf
    real(dp), intent(in) :: key, rw(:), lu(:, :)
    integer, intent(in) :: ipiv(:)
    integer :: info
    self%have_lu = .false.
    if (nf < 1 .or. nf > self%capacity .or. key == 0.0_dp) return
    call grow_dense(self, nf, info)
    if (info /= 0) return
    if (size(rw) /= nf .or. size(lu, 1) /= nf .or. size(lu, 2) /= nf .or. size(ipiv) /= nf) return
    if (any(ipiv < 1) .or. any(ipiv > nf)) return
    if (.not. (all_finite(rw) .and. all_finite(lu))) return     ! (from a file: nothing non-finite to LAPACK)
    self%rw(1:nf) = rw; self%lu(1:nf, 1:nf) = lu; self%ipiv(1:nf) = ipiv
    self%fkind = FACTORS_WHOLE
    self%lu_n = nf; self%lu_key = key
    self%have_lu = .true.
  end subroutine keep_factors

  !> No workspace and no kept factors (each array freed on its own: after an allocate that failed
  !> part-way some are allocated and some not).
  subroutine release(self)
    type(vci_newton_t), intent(inout) :: self
    call release_dense(self)
    if (allocated(self%r)) deallocate (self%r)
    if (allocated(self%sc)) deallocate (self%sc)
    if (allocated(self%dx)) deallocate (self%dx)
    if (allocated(self%xt)) deallocate (self%xt)
    if (allocated(self%rt)) deallocate (self%rt)
    if (allocated(self%sct)) deallocate (self%sct)
    if (allocated(self%sv)) deallocate (self%sv)
    if (allocated(self%ipiv)) deallocate (self%ipiv)
    if (allocated(self%rw)) deallocate (self%rw)
    if (allocated(self%brw)) deallocate (self%brw)
    if (allocated(self%bvec)) deallocate (self%bvec)
    call self%sparse%reset()
    self%fkind = FACTORS_WHOLE
    self%capacity = 0
    self%have_lu = .false.
  end subroutine release

  !> Solve sys%residual(x) = 0 for x(1:n), starting from the given x. On failure x holds the best
  !> iterate found and res says why. A small system (fewer than reuse_min unknowns, no structure)
  !> leaves a large system's kept factors kept (issue 28: an impact's impulse, solved between the
  !> sub-steps of its stage 2): it factorises in the dense lu, apart from band, sparse or block
  !> factors, and the leading n x n of kept dense factors is put back after it.
  subroutine solve(self, sys, x, res)
    class(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    real(dp), intent(inout) :: x(:)
    type(vci_newton_result_t), intent(out) :: res
    ! (fixed-size copies: an automatic array would be a heap allocation in every solve)
    integer :: n, kind0, n0, ipiv0(vci_large_system)
    real(dp) :: key0, rw0(vci_large_system), lu0(vci_large_system, vci_large_system)
    logical :: keep
    n = size(x)
    keep = n < self%reuse_min .and. n <= vci_large_system .and. self%have_lu .and. self%lu_n > n
    if (keep) then
      kind0 = self%fkind; n0 = self%lu_n; key0 = self%lu_key; rw0(1:n) = self%rw(1:n)
      if (kind0 == FACTORS_WHOLE) then
        lu0(1:n, 1:n) = self%lu(1:n, 1:n); ipiv0(1:n) = self%ipiv(1:n)
      end if
    end if
    call solve_system(self, sys, x, res)
    ! (only where the small solve used no structured or bordered storage)
    if (keep .and. self%snb == 0 .and. self%ssp == 0 .and. self%nbord == 0 .and. &
        (self%fkind == FACTORS_WHOLE .or. self%fkind == kind0)) then
      self%fkind = kind0; self%lu_n = n0; self%lu_key = key0; self%rw(1:n) = rw0(1:n)
      if (kind0 == FACTORS_WHOLE) then
        self%lu(1:n, 1:n) = lu0(1:n, 1:n); self%ipiv(1:n) = ipiv0(1:n)
      end if
      self%have_lu = .true.; self%lu_ratio = 1.0_dp
    end if
  end subroutine solve

  subroutine solve_system(self, sys, x, res)
    class(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    real(dp), intent(inout) :: x(:)
    type(vci_newton_result_t), intent(out) :: res
    integer :: n, stat, it, ib, trial_stat, i
    real(dp) :: phi, phit, step, key, ratio
    logical :: factored

    n = size(x)
    res = vci_newton_result_t()
    factored = .false.
    sys%unrecoverable = .false.
    key = 0.0_dp
    if (n >= self%reuse_min) key = sys%reuse_key()
    call pose_structure(self, sys, n)
    ! Newton's matrix in the declared band when the system writes it there, else dense
    call pose_storage(self, sys, n, stat)
    if (stat /= VCI_OK) then
      res%status = stat; res%reason = NEWTON_MEMORY; return
    end if
    ! a stage system bordered by its last unknown: the block (the first n - 1, holding any declared
    ! structure) is factorised on its own and the border eliminated
    self%nbord = 0; self%block_stale = .true.
    if (self%bordered .and. n >= max(2, self%border_min) .and. self%snb < n .and. self%ssp < n) then
      if (sys%border() == 1) self%nbord = 1
    end if
    call sys%residual(x, self%r(1:n), self%sc(1:n), stat)
    if (stat /= VCI_OK) then
      call fail_eval(res, stat); return
    end if
    if (.not. (all_finite(self%r(1:n)) .and. all_finite(self%sc(1:n)))) then
      call fail_nonfinite(res); return
    end if
    phi = merit(self, self%r(1:n), self%sc(1:n))
    res%scaled_residual = phi

    ! Simplified Newton: chord steps on the factors of an earlier solve of the same family, kept
    ! while each contracts the scaled residual by reuse_contraction or better; if they stop above
    ! the tolerance, full Newton (a new Jacobian and factors) takes over from there
    ! (factors of another key of the family serve with their directions scaled: sys%chord_ratio)
    ratio = 0.0_dp
    if (key /= 0.0_dp .and. self%have_lu .and. self%lu_n == n) then
      ratio = 1.0_dp
      if (key /= self%lu_key) ratio = sys%chord_ratio(self%lu_key)
    end if
    self%lu_ratio = 1.0_dp
    if (ratio > 0.0_dp) then
      self%lu_ratio = ratio
      factored = .true.
      do it = 1, self%max_iterations
        ! cheap steps: go on below the tolerance, to about round-off (chord steps converge linearly)
        if (phi <= 1.0e-3_dp) exit
        do i = 1, n
          self%dx(i) = self%lu_ratio * (self%r(i) * self%rw(i))
        end do
        call lu_solve(self, n, self%dx)
        self%xt(1:n) = x - self%dx(1:n)
        if (.not. sys%admissible(self%xt(1:n))) exit
        call sys%residual(self%xt(1:n), self%rt(1:n), self%sct(1:n), stat)
        if (stat /= VCI_OK .and. sys%unrecoverable) then
          call fail_eval(res, stat); return          ! a callback said so: no Newton after it
        end if
        if (stat /= VCI_OK) exit
        phit = merit(self, self%rt(1:n), self%sct(1:n))
        ! above the tolerance a chord step must contract well (else new factors pay); below it,
        ! any decrease is taken on the way to round-off
        if (.not. (phit <= self%reuse_contraction * phi .or. (phi <= 1.0_dp .and. phit < phi))) exit
        res%iterations = res%iterations + 1
        call accept_trial(self, n, x, phit, phi, res)
      end do
    end if

    do it = 1, self%max_iterations
      ! a start within the tolerance is kept only when it is at about round-off (a predictor exact
      ! for the motion); otherwise one Newton step and the polish take it there, as from any start
      if (phi <= 1.0_dp .and. (it > 1 .or. factored .or. phi <= start_roundoff)) exit
      if (self%chord_after_newton .and. it > 1 .and. factored) then
        if (chord_step(self, sys, x, n, phi, res)) cycle
        if (res%status /= VCI_OK) return
      end if
      res%iterations = res%iterations + 1
      if (self%packed) then
        call self%bmat%pose(n)
        call sys%band_jacobian(x, self%r(1:n), self%bmat, stat)
      else if (self%spacked) then
        call self%smat%pose(n)
        call sys%sparse_jacobian(x, self%r(1:n), self%smat, stat)
      else
        call sys%jacobian(x, self%r(1:n), self%jac(1:n, 1:n), stat)
      end if
      if (stat /= VCI_OK .and. phi <= 1.0_dp .and. .not. sys%unrecoverable) exit   ! (optional step: the start stands)
      if (stat /= VCI_OK) then
        call fail_eval(res, stat); return
      end if
      ! (a NaN/Inf in the Jacobian reaches the equilibrated matrix, which newton_direction checks)
      ! the kept factors are overwritten from here on: none are kept until a factorisation succeeds
      ! (a failed one left the next solve's chord steps NaN factors: fuzz seed 10217)
      self%have_lu = .false.
      call newton_direction(self, n, factored, res)
      if (res%reason == NEWTON_STRUCTURE) then
        res%status = VCI_ERR_ARGUMENT; return
      end if
      if (res%reason == NEWTON_MEMORY) then
        res%status = VCI_ERR_MEMORY; return
      end if
      if (res%reason /= NEWTON_CONVERGED .and. phi <= 1.0_dp) then
        res%reason = NEWTON_CONVERGED; factored = .false.; exit
      end if
      if (res%reason == NEWTON_NONFINITE) then
        res%status = VCI_ERR_NONFINITE; return
      end if
      self%have_lu = factored .and. key /= 0.0_dp
      self%lu_ratio = 1.0_dp
      self%lu_n = n; self%lu_key = key
      if (res%reason == NEWTON_SINGULAR) then
        res%status = VCI_ERR_NEWTON; return
      end if
      ! Backtracking on the scaled residual: halve the step until the merit decreases.
      step = 1.0_dp
      trial_stat = VCI_OK
      do ib = 0, self%max_backtracks
        self%xt(1:n) = x - step * self%dx(1:n)
        if (sys%admissible(self%xt(1:n))) then
          call sys%residual(self%xt(1:n), self%rt(1:n), self%sct(1:n), stat)
          ! an overflowing trial point is backed off from like a failed evaluation
          if (stat == VCI_OK .and. .not. (all_finite(self%rt(1:n)) .and. all_finite(self%sct(1:n)))) &
            stat = VCI_ERR_NONFINITE
          if (stat /= VCI_OK .and. sys%unrecoverable) then
            call fail_eval(res, stat); return
          end if
          if (stat /= VCI_OK) trial_stat = stat
          if (stat == VCI_OK) then
            phit = merit(self, self%rt(1:n), self%sct(1:n))
            if (phit < (1.0_dp - 1.0e-4_dp * step) * phi) exit
          end if
        end if
        step = 0.5_dp * step
      end do
      if (ib > self%max_backtracks) then
        if (phi <= 1.0_dp) exit
        if (self%fkind == FACTORS_BORDERED .and. self%block_reused) then
          self%block_stale = .true.; cycle     ! a chord direction: retry with the current block
        end if
        ! a callback that failed (or gave NaN) at the trial points is the cause, not the descent
        if (trial_stat /= VCI_OK) then
          call fail_eval(res, trial_stat); return
        end if
        res%reason = NEWTON_NO_DESCENT
        res%status = VCI_ERR_NEWTON
        return
      end if
      ! a chord on the bordered block that stopped contracting: a new block at the next iteration
      if (self%fkind == FACTORS_BORDERED .and. .not. (phit <= self%reuse_contraction * phi)) &
        self%block_stale = .true.
      if (step < 1.0_dp) res%damped = .true.
      call accept_trial(self, n, x, phit, phi, res)
    end do

    if (phi > 1.0_dp) then
      res%reason = NEWTON_MAX_ITERATIONS
      res%status = VCI_ERR_NEWTON
      return
    end if
    if (self%polish .and. factored .and. phi > 0.0_dp .and. phi * self%rtol > self%polish_above * epsilon(1.0_dp)) &
      call polish_step(self, sys, x, n, phi, res)
    if (factored .and. self%fkind == FACTORS_BORDERED) call keep_block(self, sys, x, n)
  end subroutine solve_system

  !> After a bordered solve: its block's factors (of the last direction) become the kept factors of
  !> the family sys%block_key(x) names, with the block's row weights (issue 28: stage 1's block is
  !> the sub-step matrix of length alpha tau, stage 2's that of the leaving sub-step; the sub-steps
  !> of stage 2 and the poke screen then start with chord steps on it, see chord_ratio).
  subroutine keep_block(self, sys, x, n)
    type(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    real(dp), intent(in) :: x(:)
    integer, intent(in) :: n
    real(dp) :: bkey
    bkey = sys%block_key(x(1:n))
    ! (band and sparse blocks only: a dense block's factors would be kept in no checkpoint, and a
    ! dense run's restart is bit for bit with the factors it keeps, docs/DESIGN.md)
    if (self%bkind /= FACTORS_BAND .and. self%bkind /= FACTORS_SPARSE) return
    if (bkey == 0.0_dp .or. n - 1 < self%reuse_min .or. self%block_ni /= n - 1) return
    self%fkind = self%bkind
    self%rw(1:n - 1) = self%brw(1:n - 1)
    self%have_lu = .true.; self%lu_n = n - 1; self%lu_key = bkey; self%lu_ratio = 1.0_dp
  end subroutine keep_block

  !> After a solve of n unknowns that failed on convergence (not on an evaluation): the row with
  !> the largest scaled residual at the iterate left in x (the message names its equation).
  pure integer function worst_row(self, n)
    class(vci_newton_t), intent(in) :: self
    integer, intent(in) :: n
    integer :: i
    real(dp) :: worst, v
    worst_row = 0; worst = -1.0_dp
    if (.not. allocated(self%r) .or. n > self%capacity) return
    do i = 1, n
      v = abs(self%r(i)) / max(self%atol + self%rtol * self%sc(i), tiny(1.0_dp))
      if (.not. (v <= worst)) then
        worst = v; worst_row = i
      end if
      if (.not. (v == v)) exit
    end do
  end function worst_row

  !> The trial point (xt, its residual rt and scales sct, merit phit) becomes the iterate.
  subroutine accept_trial(self, n, x, phit, phi, res)
    class(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    real(dp), intent(inout) :: x(:)
    real(dp), intent(in) :: phit
    real(dp), intent(out) :: phi
    type(vci_newton_result_t), intent(inout) :: res
    x = self%xt(1:n)
    self%r(1:n) = self%rt(1:n)
    self%sc(1:n) = self%sct(1:n)
    phi = phit
    res%scaled_residual = phi
  end subroutine accept_trial

  !> Solve the small dense system a x = b in place (b becomes x), with the solver's workspace.
  !> info /= 0: singular even for least squares, or a or b not finite (LAPACK is then not called).
  !> structured_as (optional): a system whose declared structure a has (a band, vci_banded, or a
  !> sparse pattern, vci_sparse): then a is factorised in that structure with its border, as
  !> Newton's matrices of that system are.
  subroutine linear_solve(self, n, a, b, info, structured_as)
    class(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    real(dp), intent(in) :: a(:, :)
    real(dp), intent(inout) :: b(:)
    integer, intent(out) :: info
    class(vci_system_t), intent(inout), optional :: structured_as
    integer :: snb, sbw, ssp
    logical :: chk
    type(vci_sparse_pattern_t), pointer :: spat
    ! structured_as's structure is posed for this solve; the last Newton solve's is put back after
    snb = self%snb; sbw = self%sbw; ssp = self%ssp; chk = self%scheck; spat => self%spat
    self%snb = 0; self%sbw = -1; self%ssp = 0; self%scheck = .false.
    if (present(structured_as)) call pose_structure(self, structured_as, n)
    call posed_linear_solve(self, n, a, b, info)
    self%snb = snb; self%sbw = sbw; self%ssp = ssp; self%scheck = chk; self%spat => spat
  end subroutine linear_solve

  !> b := J^{-1} b with J = dR/dx of sys at x (r = R(x), evaluated by the caller), J assembled as
  !> Newton's solves assemble it: in its declared band (vci_banded_matrix, no n x n array) when
  !> sys writes it there, else densely into jac (grown to n if smaller) and solved as linear_solve
  !> with structured_as = sys. stat: the Jacobian's own (b unchanged when it fails); info as
  !> linear_solve's.
  subroutine jacobian_solve(self, sys, x, r, jac, b, info, stat)
    class(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    real(dp), intent(in) :: x(:), r(:)
    real(dp), allocatable, intent(inout) :: jac(:, :)
    real(dp), intent(inout) :: b(:)
    integer, intent(out) :: info, stat
    integer :: n, snb, sbw, ssp, st
    logical :: chk, packed, spacked
    type(vci_sparse_pattern_t), pointer :: spat
    n = size(x)
    info = -1; st = 0
    snb = self%snb; sbw = self%sbw; ssp = self%ssp; chk = self%scheck; spat => self%spat; packed = self%packed
    spacked = self%spacked
    call pose_structure(self, sys, n)
    call choose_band(self, sys)
    if (self%packed) then
      call self%bmat%pose(n)
      call sys%band_jacobian(x, r, self%bmat, stat)
      if (stat == VCI_OK) call packed_linear_solve(self, n, b, info)
    else if (self%spacked) then
      call self%smat%pose(n)
      call sys%sparse_jacobian(x, r, self%smat, stat)
      if (stat == VCI_OK) call packed_linear_solve(self, n, b, info)
    else
      stat = VCI_OK
      if (allocated(jac)) then
        if (size(jac, 1) < n .or. size(jac, 2) < n) deallocate (jac)
      end if
      if (.not. allocated(jac)) allocate (jac(n, n), stat=st)
      if (st /= 0) stat = VCI_ERR_MEMORY
      if (stat == VCI_OK) call sys%jacobian(x, r, jac(1:n, 1:n), stat)
      if (stat == VCI_OK) call posed_linear_solve(self, n, jac, b, info)
    end if
    self%snb = snb; self%sbw = sbw; self%ssp = ssp; self%scheck = chk; self%spat => spat; self%packed = packed
    self%spacked = spacked
  end subroutine jacobian_solve

  !> linear_solve of the matrix kept in its declared structure (bmat's band or smat's sparse
  !> pattern): factorised there; when the block or its border is singular, densely from a copy
  !> (n^2, made only then), as linear_solve.
  subroutine packed_linear_solve(self, n, b, info)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    real(dp), intent(inout) :: b(:)
    integer, intent(out) :: info
    integer :: i, st
    real(dp), allocatable :: a(:, :)
    info = -1
    if (.not. (packed_rows(self, n, self%rw) <= huge(1.0_dp) .and. all_finite(b(1:n)))) return
    self%rt(1:n) = b(1:n)
    self%have_lu = .false.            ! the factors below are not a Newton matrix's
    call packed_factor(self, n, self%rw, info)
    if (info == 0) then
      do i = 1, n
        b(i) = b(i) * self%rw(i)
      end do
      call lu_solve(self, n, b)
      if (all_finite(b(1:n))) return
      b(1:n) = self%rt(1:n)
    end if
    self%fkind = FACTORS_WHOLE
    allocate (a(n, n), stat=st)
    if (st /= 0) then
      info = -1; return
    end if
    call packed_to_dense(self, a, n)
    self%snb = 0; self%ssp = 0; self%scheck = .false.
    call posed_linear_solve(self, n, a, b, info)
  end subroutine packed_linear_solve

  !> linear_solve with the posed structure (snb, sbw, ssp, spat, scheck).
  subroutine posed_linear_solve(self, n, a, b, info)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    real(dp), intent(in) :: a(:, :)
    real(dp), intent(inout) :: b(:)
    integer, intent(out) :: info
    integer :: rank, i
    logical :: band_only
    ! a declared band without the debug check: a's entries outside it were never written (read as
    ! zero below)
    band_only = self%snb > 0 .and. .not. self%scheck
    if (band_only) then
      if (.not. (band_rows(n, self%snb, self%sbw, a, size(a, 1), self%rw) <= huge(1.0_dp) .and. &
                 all_finite(b(1:n)))) then
        info = -1; return
      end if
    else if (.not. (all_finite(a(1:n, 1:n)) .and. all_finite(b(1:n)))) then
      info = -1; return
    end if
    self%rt(1:n) = b(1:n)                  ! the right-hand side, for the fallback
    self%have_lu = .false.            ! the factors below are not a Newton matrix's
    if (self%snb > 0 .or. self%ssp > 0) then
      if (structure_rows(self, n, a, size(a, 1), self%rw) <= huge(1.0_dp)) then
        call structured_factor(self, n, a, size(a, 1), self%rw, info)
        if (info == 0) then
          do i = 1, n
            b(i) = b(i) * self%rw(i)
          end do
          call lu_solve(self, n, b)
          if (all_finite(b(1:n))) return
          b(1:n) = self%rt(1:n)
        end if
      end if
    end if
    call grow_dense(self, n, info)
    if (info /= 0) then
      b(1:n) = self%rt(1:n); info = -1; return
    end if
    self%lu(1:n, 1:n) = a(1:n, 1:n)
    if (band_only) call zero_outside_band(self%snb, self%sbw, self%lu, self%dense_capacity)
    call lu_factor(self, n, info)
    if (info == 0) then
      call lu_solve(self, n, b)
      if (all_finite(b(1:n))) return
    end if
    ! singular: the minimum-norm least-squares solution, as in the Newton direction
    self%jac(1:n, 1:n) = a(1:n, 1:n)
    if (band_only) call zero_outside_band(self%snb, self%sbw, self%jac, self%dense_capacity)
    self%dx(1:n) = self%rt(1:n)
    call dgelsd(n, n, 1, self%jac, self%dense_capacity, self%dx, self%capacity, self%sv, 1.0e-12_dp, rank, &
                self%work, size(self%work), self%iwork, info)
    if (info == 0 .and. all_finite(self%dx(1:n))) then
      b(1:n) = self%dx(1:n)
    else
      b(1:n) = self%rt(1:n)
      if (info == 0) info = -1
    end if
  end subroutine posed_linear_solve

  !> Newton direction dx = J^{-1} r on the row-equilibrated system; least squares when singular.
  !> A stage system's border is eliminated with its block's factors (bordered_direction), a declared
  !> structure is factorised in it (structured_direction); when those fail (a singular block or
  !> Schur complement, a cancelling border, no memory) the whole matrix is factorised densely.
  subroutine newton_direction(self, n, factored, res)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    logical, intent(out) :: factored
    type(vci_newton_result_t), intent(inout) :: res
    integer :: i, info, rank
    factored = .false.
    if (outside_structure(self, res)) return
    if (self%nbord == 1) then
      call bordered_direction(self, n, factored)
      if (factored) return
    end if
    if (self%snb > 0 .or. self%ssp > 0) then
      call structured_direction(self, n, factored)
      if (factored) return
      ! a singular band block or Schur complement (or no workspace, no KLU): the dense path below
      ! decides, on the matrix with its zeros outside the band written (the assembly wrote the band
      ! alone; a sparse pattern's matrix is dense in memory); a matrix kept in its band is copied
      ! out to a dense one, made (n^2) only now
      if (self%packed .or. self%spacked) then
        call grow_dense(self, n, info)
        if (info /= 0) then
          res%reason = NEWTON_MEMORY; return
        end if
        call packed_to_dense(self, self%jac, self%dense_capacity)
      else if (self%snb > 0 .and. .not. self%scheck) then
        call zero_outside_band(self%snb, self%sbw, self%jac, self%dense_capacity)
      end if
    end if
    ! rows equilibrated by their largest entry; jac keeps the equilibrated matrix for the fallback
    call equilibrate(n, self%dense_capacity, self%jac, self%lu, self%r, self%dx, self%rw)
    factored = .false.
    ! r w overflows when r is huge and the row's entries tiny: nothing non-finite goes to LAPACK
    if (.not. (all_finite(self%lu(1:n, 1:n)) .and. all_finite(self%dx(1:n)))) then
      res%reason = NEWTON_NONFINITE; return
    end if
    call lu_factor(self, n, info)
    self%factorisations = self%factorisations + 1
    factored = .false.
    if (info == 0) then
      if (pivots_regular(n, self%dense_capacity, self%lu)) then
        call lu_solve(self, n, self%dx)
        factored = all(ieee_is_finite(self%dx(1:n)))
      end if
    end if
    if (factored) return
    ! Singular (or numerically so): minimum-norm least-squares step, rank decided at 1e-12.
    do i = 1, n
      self%dx(i) = self%r(i) * self%rw(i)
    end do
    call dgelsd(n, n, 1, self%jac, self%dense_capacity, self%dx, self%capacity, self%sv, 1.0e-12_dp, rank, &
                self%work, size(self%work), self%iwork, info)
    res%used_fallback = .true.
    if (info /= 0 .or. .not. all(ieee_is_finite(self%dx(1:n)))) res%reason = NEWTON_SINGULAR
  end subroutine newton_direction

  !> The debug check of a declared structure (scheck): true, with res%reason NEWTON_STRUCTURE and
  !> the entry, when the Newton matrix has a nonzero outside the band or the pattern.
  logical function outside_structure(self, res) result(outside)
    type(vci_newton_t), intent(inout) :: self
    type(vci_newton_result_t), intent(inout) :: res
    integer :: i, j
    outside = .false.
    if (.not. self%scheck) return
    i = 0; j = 0
    if (self%snb > 0) then
      call outside_band(self%snb, self%sbw, self%jac, self%dense_capacity, i, j)
    else if (self%ssp > 0) then
      call outside_pattern(self%ssp, self%spat, self%jac, self%dense_capacity, i, j)
    end if
    if (i > 0) then
      res%reason = NEWTON_STRUCTURE; res%bad_row = i; res%bad_col = j; outside = .true.
    end if
  end function outside_structure

  !> Newton direction for a system bordered by its last unknown (vci_bordered): the block
  !> jac(1:n-1, 1:n-1), in its declared structure (band or sparse pattern with their own border,
  !> else dense), factorised when stale (else its factors from an earlier iteration of this solve: a
  !> chord on the block), the current border eliminated. factored false: the whole matrix is
  !> factorised instead (singular block, cancelling Schur complement, NaN/Inf: the whole path
  !> reports those). rw = 1: the bordered solve equilibrates the block's rows itself (brw).
  subroutine bordered_direction(self, n, factored)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    logical, intent(out) :: factored
    integer :: info, ni
    factored = .false.
    ni = n - 1
    self%block_reused = .true.
    ! (the chord only on a dense block of more than reuse_min unknowns: below, and for a band or
    ! sparse block at any size, a factorisation costs less than the extra iterations a chord takes,
    ! each with its residual and Jacobian: docs/bench/bordered.md)
    if (self%block_stale .or. .not. self%border_chord .or. n <= self%reuse_min .or. self%block_ni /= ni .or. &
        self%snb > 0 .or. self%ssp > 0) then
      self%block_stale = .true.
      if (self%packed .or. self%spacked) then
        if (.not. (packed_rows(self, ni, self%brw) <= huge(1.0_dp))) return
        call packed_factor(self, ni, self%brw, info)
      else
        if (.not. (structure_rows(self, ni, self%jac, self%dense_capacity, self%brw) <= huge(1.0_dp))) return
        call structured_factor(self, ni, self%jac, self%dense_capacity, self%brw, info)
      end if
      if (info /= 0) return
      self%bkind = self%fkind; self%block_ni = ni
      self%factorisations = self%factorisations + 1
      if (self%bkind /= FACTORS_BLOCK) self%structured_factorisations = self%structured_factorisations + 1
      self%block_stale = .false.; self%block_reused = .false.
    end if
    if (self%packed) then
      ! the border's row: the last border row over the band block's columns, then the last row of
      ! the other border columns (the multipliers')
      associate (mt => self%bmat, nb => self%bmat%nb, nd => self%bmat%nd)
        self%bvec(1:nb) = mt%rows(nd, 1:nb)
        self%bvec(nb + 1:ni) = mt%cols(n, 1:nd - 1)
        call self%bord%border_parts(self%band, ni, mt%cols(1:ni, nd), self%bvec(1:ni), mt%cols(n, nd), self%brw, info)
      end associate
    else if (self%spacked) then
      associate (mt => self%smat, nb => self%smat%nb, nd => self%smat%nd)
        self%bvec(1:nb) = mt%rows(nd, 1:nb)
        self%bvec(nb + 1:ni) = mt%cols(n, 1:nd - 1)
        call self%bord%border_parts(self%sparse, ni, mt%cols(1:ni, nd), self%bvec(1:ni), mt%cols(n, nd), self%brw, &
                                    info)
      end associate
    else
      select case (self%bkind)
      case (FACTORS_BAND)
        call self%bord%border(self%band, ni, self%jac, self%dense_capacity, self%brw, info)
      case (FACTORS_SPARSE)
        call self%bord%border(self%sparse, ni, self%jac, self%dense_capacity, self%brw, info)
      case default
        call self%bord%border(self%blockd, ni, self%jac, self%dense_capacity, self%brw, info)
      end select
    end if
    if (info /= 0) then
      self%block_stale = .true.; return
    end if
    self%rw(1:n) = 1.0_dp
    self%dx(1:n) = self%r(1:n)
    self%fkind = FACTORS_BORDERED
    call lu_solve(self, n, self%dx)
    factored = all(ieee_is_finite(self%dx(1:n)))
    if (.not. factored) then
      self%block_stale = .true.; return
    end if
    self%bordered_directions = self%bordered_directions + 1
  end subroutine bordered_direction

  !> Newton direction for a system that declared structure (a band, vci_banded, or a sparse
  !> pattern, vci_sparse; each with its dense border): rows equilibrated by their largest entry in
  !> the structure and the border, the matrix factorised in its structure. factored false: fall
  !> back to the dense path (jac untouched).
  subroutine structured_direction(self, n, factored)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    logical, intent(out) :: factored
    integer :: i, info
    real(dp) :: total
    factored = .false.
    if (self%packed .or. self%spacked) then
      total = packed_rows(self, n, self%rw)
    else
      total = structure_rows(self, n, self%jac, self%dense_capacity, self%rw)
    end if
    do i = 1, n
      self%dx(i) = self%r(i) * self%rw(i)
    end do
    ! NaN/Inf in the matrix or r w: the dense path reports it (nothing non-finite goes to LAPACK)
    if (.not. (total <= huge(1.0_dp) .and. all_finite(self%dx(1:n)))) return
    if (self%packed .or. self%spacked) then
      call packed_factor(self, n, self%rw, info)
    else
      call structured_factor(self, n, self%jac, self%dense_capacity, self%rw, info)
    end if
    if (info /= 0) return
    self%factorisations = self%factorisations + 1
    self%structured_factorisations = self%structured_factorisations + 1
    call lu_solve(self, n, self%dx)
    factored = all(ieee_is_finite(self%dx(1:n)))
  end subroutine structured_direction

  !> packed: Newton's matrix goes into the declared band (bmat, sized here) when the system writes
  !> it there, the debug check is off (the check scans a dense matrix) and the band storage fits.
  subroutine choose_band(self, sys)
    type(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    integer :: st
    self%packed = .false.; self%spacked = .false.
    if (self%snb > 0 .and. .not. self%scheck) then
      if (sys%packs_band()) then
        call self%bmat%size_for(self%snb, self%sbw, self%capacity - self%snb, st)
        self%packed = st == 0
      end if
    else if (self%ssp > 0 .and. .not. self%scheck) then
      if (sys%packs_sparse()) then
        call self%smat%size_for(self%spat, self%capacity - self%ssp, st)
        self%spacked = st == 0
      end if
    end if
  end subroutine choose_band

  !> packed_rows / packed_factor / packed_to_dense: the matrix kept in its declared structure (band
  !> in bmat, or sparse pattern in smat) — row weights of its leading nx x nx, its factors (fkind
  !> names them; FACTORS_WHOLE when they failed), its dense copy for the fallback.
  real(dp) function packed_rows(self, nx, rw) result(total)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: nx
    real(dp), intent(out) :: rw(:)
    if (self%spacked) then
      total = self%smat%row_weights(nx, rw)
    else
      total = self%bmat%row_weights(nx, rw)
    end if
  end function packed_rows

  !> Factorise diag(rw) times the leading nx x nx of the packed matrix in its structure.
  subroutine packed_factor(self, nx, rw, info)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: nx
    real(dp), intent(in) :: rw(:)
    integer, intent(out) :: info
    if (self%spacked) then
      call self%sparse%factor_parts(nx, self%smat%nb, self%smat%pat, self%smat%val, self%smat%rows, &
                                    self%smat%cols, rw, info)
      self%fkind = FACTORS_SPARSE
    else
      call self%band%factor_packed(nx, self%bmat, rw, info)
      self%fkind = FACTORS_BAND
    end if
    if (info /= 0) self%fkind = FACTORS_WHOLE
  end subroutine packed_factor

  !> a(1:nx, 1:nx) = the packed matrix (O(nx^2): the dense fallback only).
  subroutine packed_to_dense(self, a, lda)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: lda
    real(dp), intent(inout) :: a(lda, *)
    if (self%spacked) then
      call self%smat%to_dense(a, lda)
    else
      call self%bmat%to_dense(a, lda)
    end if
  end subroutine packed_to_dense

  !> Where this solve keeps Newton's matrix: in the declared band (bmat, packed) when the system
  !> writes it there and the debug check is off (the check scans a dense matrix), else in the dense
  !> jac, grown to n unknowns if reserve sized it smaller. stat: VCI_ERR_MEMORY when neither fits.
  subroutine pose_storage(self, sys, n, stat)
    type(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    integer, intent(in) :: n
    integer, intent(out) :: stat
    integer :: st
    stat = VCI_OK
    call choose_band(self, sys)
    if (self%packed .or. self%spacked) return
    call grow_dense(self, n, st)
    if (st /= 0) stat = VCI_ERR_MEMORY
  end subroutine pose_storage

  !> The posed structure of sys (n unknowns): a band (snb, sbw) or else a sparse pattern (ssp,
  !> spat), and whether to check it on every matrix (scheck).
  subroutine pose_structure(self, sys, n)
    type(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    integer, intent(in) :: n
    call sys%structure(self%snb, self%sbw, self%scheck)
    if (self%snb > n .or. self%sbw < 0) self%snb = 0
    self%ssp = 0
    if (self%snb == 0) call sparse_posed(self, sys, n)
  end subroutine pose_structure

  !> The system's declared sparse pattern, if it has one that fits n unknowns: ssp, spat, scheck.
  subroutine sparse_posed(self, sys, n)
    type(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    integer, intent(in) :: n
    integer :: nb
    logical :: chk
    self%ssp = 0
    call sys%sparse_structure(nb, self%spat, chk)
    if (.not. associated(self%spat)) return
    if (nb < 1 .or. nb > n .or. self%spat%n /= nb) return
    self%ssp = nb; self%scheck = chk
  end subroutine sparse_posed

  !> rw(i) = 1 / the largest |a(i, j)| of row i of a(1:n, 1:n) over the posed structure (band or
  !> pattern) and the border, or over the whole row when none is declared; returns the sum of those
  !> maxima (not finite: a NaN or Inf in the matrix).
  real(dp) function structure_rows(self, n, a, lda, rw) result(total)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n, lda
    real(dp), intent(in) :: a(lda, *)
    real(dp), intent(out) :: rw(:)
    integer :: i, j
    real(dp) :: big
    if (self%snb > 0) then
      total = band_rows(n, self%snb, self%sbw, a, lda, rw)
    else if (self%ssp > 0) then
      total = pattern_rows(n, self%ssp, self%spat, a, lda, rw)
    else
      total = 0.0_dp
      do i = 1, n
        big = 0.0_dp
        do j = 1, n
          big = max(big, abs(a(i, j)))
        end do
        total = total + big
        rw(i) = 1.0_dp
        if (big > 0.0_dp) rw(i) = 1.0_dp / big
      end do
    end if
  end function structure_rows

  !> Factorise diag(rw) a(1:n, 1:n) in the posed structure — band (vci_banded), sparse pattern
  !> (vci_sparse) or, with none, the dense block LU (vci_factor) — into the factors of that kind;
  !> fkind names them (lu_solve then solves with them). n may be the posed system's unknowns or its
  !> bordered block's (n - 1). info /= 0: not factorised (singular, no workspace, no KLU).
  subroutine structured_factor(self, n, a, lda, rw, info)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n, lda
    real(dp), intent(in) :: a(lda, *), rw(:)
    integer, intent(out) :: info
    if (self%snb > 0) then
      call self%band%factor(n, self%snb, self%sbw, a, lda, rw, info)
      self%fkind = FACTORS_BAND
    else if (self%ssp > 0) then
      call self%sparse%factor(n, self%ssp, self%spat, a, lda, rw, info)
      self%fkind = FACTORS_SPARSE
    else
      call self%blockd%factor(n, a, lda, rw, self%small_lu_max, info)
      self%fkind = FACTORS_BLOCK
    end if
    if (info /= 0) self%fkind = FACTORS_WHOLE     ! (lu_solve must not use factors that failed)
  end subroutine structured_factor

  !> rw(i) = 1 / the largest |a(i, j)| of row i over the band and the border (the entries outside the
  !> band are zero); returns the sum of those maxima (not finite: a NaN or Inf in the matrix).
  real(dp) function band_rows(n, nb, bw, a, lda, rw) result(total)
    integer, intent(in) :: n, nb, bw, lda
    real(dp), intent(in) :: a(lda, *)
    real(dp), intent(out) :: rw(:)
    integer :: i, j
    real(dp) :: big
    total = 0.0_dp
    do i = 1, n
      big = 0.0_dp
      if (i <= nb) then
        do j = max(1, i - bw), min(nb, i + bw)
          big = max(big, abs(a(i, j)))
        end do
        do j = nb + 1, n
          big = max(big, abs(a(i, j)))
        end do
      else
        do j = 1, n
          big = max(big, abs(a(i, j)))
        end do
      end if
      total = total + big
      rw(i) = 1.0_dp
      if (big > 0.0_dp) rw(i) = 1.0_dp / big
    end do
  end function band_rows

  !> a(i, j) = 0 for i, j <= nb with |i - j| > bw: the zeros of a declared band, which a structured
  !> assembly does not write (O(nb^2): only before a dense fallback).
  pure subroutine zero_outside_band(nb, bw, a, lda)
    integer, intent(in) :: nb, bw, lda
    real(dp), intent(inout) :: a(lda, *)
    integer :: i, j
    do j = 1, nb
      do i = 1, j - bw - 1
        a(i, j) = 0.0_dp
      end do
      do i = j + bw + 1, nb
        a(i, j) = 0.0_dp
      end do
    end do
  end subroutine zero_outside_band

  !> One chord step with the last LU factors; kept only if it does not make the residual worse.
  !> One chord step on the factors of the last Newton matrix (chord_after_newton): true when it was
  !> taken (the scaled residual at or below the tolerance, or contracted by reuse_contraction). A
  !> failed evaluation or a step not taken leaves x and phi as they were (full Newton goes on), unless
  !> the callback said unrecoverable (res%status set).
  logical function chord_step(self, sys, x, n, phi, res) result(taken)
    type(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    real(dp), intent(inout) :: x(:)
    integer, intent(in) :: n
    real(dp), intent(inout) :: phi
    type(vci_newton_result_t), intent(inout) :: res
    integer :: i, stat
    real(dp) :: phit
    taken = .false.
    do i = 1, n
      self%dx(i) = self%lu_ratio * (self%r(i) * self%rw(i))
    end do
    if (.not. all_finite(self%dx(1:n))) return
    call lu_solve(self, n, self%dx)
    self%xt(1:n) = x - self%dx(1:n)
    if (.not. sys%admissible(self%xt(1:n))) return
    call sys%residual(self%xt(1:n), self%rt(1:n), self%sct(1:n), stat)
    if (stat /= VCI_OK .and. sys%unrecoverable) call fail_eval(res, stat)
    if (stat /= VCI_OK) return
    if (.not. (all_finite(self%rt(1:n)) .and. all_finite(self%sct(1:n)))) return
    phit = merit(self, self%rt(1:n), self%sct(1:n))
    if (.not. (phit <= 1.0_dp .or. phit <= self%reuse_contraction * phi)) return
    res%iterations = res%iterations + 1
    call accept_trial(self, n, x, phit, phi, res)
    taken = .true.
  end function chord_step

  subroutine polish_step(self, sys, x, n, phi, res)
    type(vci_newton_t), intent(inout) :: self
    class(vci_system_t), intent(inout) :: sys
    real(dp), intent(inout) :: x(:)
    integer, intent(in) :: n
    real(dp), intent(in) :: phi
    type(vci_newton_result_t), intent(inout) :: res
    integer :: i, stat
    real(dp) :: phit
    do i = 1, n
      self%dx(i) = self%lu_ratio * (self%r(i) * self%rw(i))
    end do
    if (.not. all_finite(self%dx(1:n))) return
    call lu_solve(self, n, self%dx)
    self%xt(1:n) = x - self%dx(1:n)
    if (.not. sys%admissible(self%xt(1:n))) return
    call sys%residual(self%xt(1:n), self%rt(1:n), self%sct(1:n), stat)
    ! an optional step: a failure keeps the converged x, unless the callback said unrecoverable
    if (stat /= VCI_OK .and. sys%unrecoverable) call fail_eval(res, stat)
    if (stat /= VCI_OK) return
    if (.not. (all_finite(self%rt(1:n)) .and. all_finite(self%sct(1:n)))) return
    phit = merit(self, self%rt(1:n), self%sct(1:n))
    res%iterations = res%iterations + 1
    if (phit <= phi) then
      x = self%xt(1:n)
      res%scaled_residual = phit
    end if
  end subroutine polish_step

  !> LU factorisation with partial pivoting of lu(1:n, 1:n) in place (LAPACK dgetrf, or the in-line
  !> elimination for n <= small_lu_max); info as dgetrf's (k > 0: U(k, k) = 0).
  subroutine lu_factor(self, n, info)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    integer, intent(out) :: info
    self%fkind = FACTORS_WHOLE
    if (n <= self%small_lu_max) then
      call small_lu(n, self%lu, self%ipiv, info)
    else
      call dgetrf(n, n, self%lu, self%dense_capacity, self%ipiv, info)
    end if
  end subroutine lu_factor

  !> b := A^{-1} b with the factors of lu_factor (dgetrs 'N' with one right-hand side).
  subroutine lu_solve(self, n, b)
    type(vci_newton_t), intent(inout) :: self
    integer, intent(in) :: n
    real(dp), intent(inout) :: b(:)
    integer :: info
    select case (self%fkind)
    case (FACTORS_BAND)
      call self%band%solve(b(1:n))
    case (FACTORS_SPARSE)
      call self%sparse%solve(b(1:n))
    case (FACTORS_BLOCK)
      call self%blockd%solve(b(1:n))
    case (FACTORS_BORDERED)           ! the bordered block's factors, of their own kind
      select case (self%bkind)
      case (FACTORS_BAND)
        call self%bord%solve(self%band, b(1:n))
      case (FACTORS_SPARSE)
        call self%bord%solve(self%sparse, b(1:n))
      case default
        call self%bord%solve(self%blockd, b(1:n))
      end select
    case default
      if (n <= self%small_lu_max) then
        call small_lu_solve(n, self%lu, self%ipiv, b)
      else
        call dgetrs('N', n, 1, self%lu, self%dense_capacity, self%ipiv, b, size(b), info)
      end if
    end select
  end subroutine lu_solve



  pure real(dp) function merit(self, r, sc)
    type(vci_newton_t), intent(in) :: self
    real(dp), intent(in) :: r(:), sc(:)
    merit = scaled_merit(size(r), r, sc, self%atol, self%rtol)
  end function merit

  !> No NaN or Inf in a (any rank: assumed-rank is F2018, so vectors and matrices separately).
  pure logical function all_finite_1(a) result(ok)
    real(dp), intent(in) :: a(:)
    integer :: i
    ok = .true.
    if (abs(sum(a)) <= huge(1.0_dp)) return   ! all finite: one test on the sum (else look at each)
    do i = 1, size(a)
      if (.not. (abs(a(i)) <= huge(1.0_dp))) then
        ok = .false.; return
      end if
    end do
  end function all_finite_1

  pure logical function all_finite_2(a) result(ok)
    real(dp), intent(in) :: a(:, :)
    integer :: j
    ok = .true.
    do j = 1, size(a, 2)
      ok = all_finite_1(a(:, j))
      if (.not. ok) return
    end do
  end function all_finite_2

  subroutine fail_nonfinite(res)
    type(vci_newton_result_t), intent(inout) :: res
    res%reason = NEWTON_NONFINITE
    res%status = VCI_ERR_NONFINITE
  end subroutine fail_nonfinite

  subroutine fail_eval(res, stat)
    type(vci_newton_result_t), intent(inout) :: res
    integer, intent(in) :: stat
    res%reason = NEWTON_EVALUATION
    res%status = stat
  end subroutine fail_eval
end module vci_newton
