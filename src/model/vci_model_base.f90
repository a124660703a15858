!> What discrete and continuous models share: the sizes, the constraint one-forms, the walls (gap
!> functions) and an optional step-independent energy H(q, p). `vci_model_t` (a discrete Lagrangian
!> L_d) and `vci_lagrangian_t` (a continuous Lagrangian L) both extend it, so the stepper treats walls,
!> constraints and the Hamiltonian impact condition the same way whichever the user wrote.
!>
!> The optional procedures answer "not provided" until overridden, on a channel of their own: they
!> call `self%not_provided(stat)`, which marks the model; the library probes an optional procedure
!> once (`clear_not_provided`, call, `answered_not_provided`) and then does without it (m = 0,
!> n_gaps = 0) or differences it (gap gradients). `stat` only ever carries the callback contract
!> (vci_model: 0 success, > 0 recoverable failure, < 0 unrecoverable), so a model that reports
!> failure with any value, -1 included, is read as failing, never as "not provided".
!> Every procedure receives `stat` preset to 0 and never stops the program.
module vci_model_base
  use vci_kinds, only: dp
  use vci_sparse, only: vci_sparse_pattern_t, make_pattern
  implicit none
  private

  !> Sizes, constraint one-forms, walls and energy: what vci_model_t and vci_lagrangian_t share.
  type, abstract, public :: vci_model_base_t
    integer :: n = 0        !< configuration dimension
    integer :: m = 0        !< number of constraint one-forms (0: unconstrained)
    integer :: n_gaps = 0   !< number of gap functions g_j(q) >= 0 bounding the admissible set
    !> Declared half-bandwidth of the Hessian blocks (L_qq, L_qv, L_vv of L, or D1 D2 L_d): entries
    !> (i, j) with |i - j| > hessian_bandwidth are zero; the schemes then factorise their Newton
    !> matrices in band storage (docs/DESIGN.md, "Structured Newton matrices"). -1: dense (default).
    integer :: hessian_bandwidth = -1
    !> With a declared band: check every Newton matrix for a nonzero outside it (a debug check,
    !> O(n^2) per factorisation); the solve then fails with a message naming the entry.
    logical :: check_bandwidth = .false.
    !> Declared sparse pattern of the Hessian blocks (declare_pattern; n = 0: none): the schemes
    !> then factorise their Newton matrices by sparse LU (vci_sparse, SuiteSparse KLU).
    type(vci_sparse_pattern_t) :: hessian_pattern
    logical :: check_pattern = .false.          !< verify the pattern on every Newton matrix (debug)
    integer :: pattern_status = 0               !< 0, or 1 when the last declare_pattern was invalid
    character(len=160) :: pattern_message = ''  !< why the last declared pattern was invalid
    logical, private :: declined = .false.   !< an optional procedure answered "not provided"
  contains
    !> Declare the Hessian blocks banded with half-bandwidth bw (bw < 0: dense); check (optional):
    !> verify the band on every Newton matrix (debug).
    procedure, non_overridable :: declare_bandwidth
    !> Declare the Hessian blocks sparse with a pattern in compressed columns (issue 28).
    procedure, non_overridable :: declare_pattern
    !> Called by an optional procedure the model does not supply, instead of computing: marks "not provided".
    procedure, non_overridable :: not_provided
    !> Start a probe: forget any earlier "not provided".
    procedure, non_overridable :: clear_not_provided
    !> Did a procedure called since clear_not_provided answer "not provided"?
    procedure, non_overridable :: answered_not_provided
    !> omega(:, mu) = components of the one-form omega^mu at q (n x m).
    procedure :: constraint_forms => not_provided_forms
    !> Gap functions g(j) = g_j(q); the admissible set is {q : g_j(q) >= 0 for all j}.
    procedure :: gaps => not_provided_gaps
    !> dg(:, j) = gradient of g_j at q (n x n_gaps).
    procedure :: gap_gradients => not_provided_gap_grads
    !> dg = gradient of g_j alone at q (n): optional, for many walls that each touch few coordinates
    !> (O(n) a wall where gap_gradients is O(n n_gaps)); used where one wall's gradient is needed.
    procedure :: gap_gradient => not_provided_gap_grad
    !> A step-independent energy H(q, p), normally the Hamiltonian (for the 'hamiltonian' impact condition).
    procedure :: energy => not_provided_energy
  end type vci_model_base_t

contains

  !> Declare the Hessian blocks banded with half-bandwidth bw (entries with |i - j| > bw are zero;
  !> bw < 0: dense, the default). check (optional, default false): verify it on every Newton matrix.
  subroutine declare_bandwidth(self, bw, check)
    class(vci_model_base_t), intent(inout) :: self
    integer, intent(in) :: bw
    logical, intent(in), optional :: check
    self%hessian_bandwidth = max(bw, -1)
    ! a band of n - 1 covers the matrix: no more storage than that (bw = 1e9 zeroed 3 (2 bw + 1) n doubles)
    if (self%n > 0) self%hessian_bandwidth = min(self%hessian_bandwidth, self%n - 1)
    self%check_bandwidth = .false.
    if (present(check)) self%check_bandwidth = check
  end subroutine declare_bandwidth

  !> Declare the sparse pattern of the Hessian blocks (L_qq, L_qv, L_vv of L, or D1 D2 L_d) in
  !> compressed columns: column j's nonzero rows are rowind(colptr(j) : colptr(j + 1) - 1) (1-based,
  !> any order; the pattern is made symmetric and given its diagonal). Entries outside it must be
  !> zero. Needs a build with VCI_SPARSE (SuiteSparse KLU): without it, or with an invalid pattern,
  !> creating an integrator for the model fails with VCI_ERR_ARGUMENT and a message saying why.
  !> check (optional, default false): verify the pattern on every Newton matrix (debug, O(n^2)).
  !> An empty colptr (size 0) withdraws the declaration.
  subroutine declare_pattern(self, colptr, rowind, check)
    class(vci_model_base_t), intent(inout) :: self
    integer, intent(in) :: colptr(:), rowind(:)
    logical, intent(in), optional :: check
    self%check_pattern = .false.
    if (present(check)) self%check_pattern = check
    self%pattern_status = 0; self%pattern_message = ''
    self%hessian_pattern = vci_sparse_pattern_t()
    if (size(colptr) == 0) return
    call make_pattern(size(colptr) - 1, colptr, rowind, self%hessian_pattern, self%pattern_status, self%pattern_message)
    if (self%pattern_status /= 0) self%pattern_status = 1
  end subroutine declare_pattern

  !> Called by an optional procedure the model does not supply (the defaults below, or an adapter
  !> whose callback is absent) instead of computing: marks the answer as "not provided" and sets
  !> stat to a failure, so that a call the library did not probe first can never pass for a value.
  subroutine not_provided(self, stat)
    class(vci_model_base_t), intent(inout) :: self
    integer, intent(inout) :: stat
    self%declined = .true.
    stat = 1
  end subroutine not_provided

  !> Start a probe: forget any earlier "not provided".
  subroutine clear_not_provided(self)
    class(vci_model_base_t), intent(inout) :: self
    self%declined = .false.
  end subroutine clear_not_provided

  !> Did a procedure called since clear_not_provided answer "not provided"?
  pure logical function answered_not_provided(self)
    class(vci_model_base_t), intent(in) :: self
    answered_not_provided = self%declined
  end function answered_not_provided

  !> omega(:, mu) = components of the one-form omega^mu at q (n x m).
  subroutine not_provided_forms(self, q, omega, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    omega = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_forms

  !> Gap functions g(j) = g_j(q); the admissible set is {q : g_j(q) >= 0 for all j}.
  subroutine not_provided_gaps(self, q, g, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_gaps

  !> dg(:, j) = gradient of g_j at q (n x n_gaps).
  subroutine not_provided_gap_grads(self, q, dg, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_gap_grads

  !> dg = gradient of g_j alone at q (n).
  subroutine not_provided_gap_grad(self, q, j, dg, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: j
    real(dp), intent(out) :: dg(:)
    integer, intent(inout) :: stat
    dg = 0.0_dp
    if (j < 0) return
    call self%not_provided(stat)
  end subroutine not_provided_gap_grad

  !> A step-independent energy H(q, p), normally the Hamiltonian; needed only for the
  !> 'hamiltonian' impact condition (a continuous model gets it by Legendre inversion when absent).
  subroutine not_provided_energy(self, q, p, e, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_energy
end module vci_model_base
