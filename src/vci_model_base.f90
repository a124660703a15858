!> What discrete and continuous models share: the sizes, the constraint one-forms, the walls (gap
!> functions) and an optional step-independent energy H(q, p). `vci_model_t` (a discrete Lagrangian
!> L_d) and `vci_lagrangian_t` (a continuous Lagrangian L) both extend it, so the stepper treats walls,
!> constraints and the Hamiltonian impact condition the same way whichever the user wrote.
!>
!> The optional procedures answer VCI_NOT_PROVIDED until overridden; the library then does without
!> them (m = 0, n_gaps = 0) or differences them (gap gradients). Every procedure receives `stat`
!> preset to 0; a callback sets it nonzero to report failure and never stops the program.
module vci_model_base
  use vci_kinds, only: dp
  use vci_status, only: VCI_NOT_PROVIDED
  implicit none
  private

  type, abstract, public :: vci_model_base_t
    integer :: n = 0        !< configuration dimension
    integer :: m = 0        !< number of constraint one-forms (0: unconstrained)
    integer :: n_gaps = 0   !< number of gap functions g_j(q) >= 0 bounding the admissible set
  contains
    procedure :: constraint_forms => not_provided_forms
    procedure :: gaps => not_provided_gaps
    procedure :: gap_gradients => not_provided_gap_grads
    procedure :: energy => not_provided_energy
  end type vci_model_base_t

contains

  !> omega(:, mu) = components of the one-form omega^mu at q (n x m).
  subroutine not_provided_forms(self, q, omega, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    omega = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_forms

  !> Gap functions g(j) = g_j(q); the admissible set is {q : g_j(q) >= 0 for all j}.
  subroutine not_provided_gaps(self, q, g, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_gaps

  !> dg(:, j) = gradient of g_j at q (n x n_gaps).
  subroutine not_provided_gap_grads(self, q, dg, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_gap_grads

  !> A step-independent energy H(q, p), normally the Hamiltonian; needed only for the
  !> 'hamiltonian' impact condition (a continuous model gets it by Legendre inversion when absent).
  subroutine not_provided_energy(self, q, p, e, stat)
    class(vci_model_base_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_energy
end module vci_model_base
