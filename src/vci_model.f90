!> The abstract model a user extends: a discrete Lagrangian L_d(q, v, h) and, only when the scene
!> needs them, nonholonomic constraints, walls (gap functions) and analytic Jacobians.
!>
!> Required: d1, d2, d3 (partials of L_d). Everything else has a default that tells the library
!> "not provided" (status VCI_NOT_PROVIDED); the library then either does without it (m = 0:
!> no multipliers; n_gaps = 0: no impact detection) or differences it (mixed Hessian, gap gradients).
!>
!> Every procedure receives `stat` preset to 0. The callback contract (as SUNDIALS'): leave it 0 on
!> success; set it > 0 for a recoverable failure (at a trial point of Newton's line search the
!> solver backs off to a shorter step; anywhere else the step fails with VCI_ERR_CALLBACK); set it
!> < 0 for an unrecoverable one (the step fails at once with VCI_ERR_CALLBACK). NaN or Inf outputs
!> count as recoverable failures (VCI_ERR_NONFINITE if they end the step). Never stop the program
!> from a callback.
module vci_model
  use vci_kinds, only: dp
  use vci_status, only: VCI_NOT_PROVIDED
  implicit none
  private

  type, abstract, public :: vci_model_t
    integer :: n = 0        !< configuration dimension
    integer :: m = 0        !< number of constraint one-forms (0: unconstrained)
    integer :: n_gaps = 0   !< number of gap functions g_j(q) >= 0 bounding the admissible set
  contains
    procedure(ld_partial), deferred :: d1   !< D1 L_d(q, v, h) in R^n
    procedure(ld_partial), deferred :: d2   !< D2 L_d(q, v, h) in R^n
    procedure(ld_dh), deferred :: d3        !< D3 L_d(q, v, h) = dL_d/dh; E_d = -D3 L_d
    procedure :: mixed_hessian => not_provided_hessian
    procedure :: constraint_forms => not_provided_forms
    procedure :: discrete_constraint => not_provided_dconstraint
    procedure :: gaps => not_provided_gaps
    procedure :: gap_gradients => not_provided_gap_grads
    procedure :: energy => not_provided_energy
  end type vci_model_t

  abstract interface
    subroutine ld_partial(self, q, v, h, out, stat)
      import :: vci_model_t, dp
      class(vci_model_t), intent(inout) :: self
      real(dp), intent(in) :: q(:), v(:), h
      real(dp), intent(out) :: out(:)
      integer, intent(inout) :: stat
    end subroutine ld_partial
    subroutine ld_dh(self, q, v, h, out, stat)
      import :: vci_model_t, dp
      class(vci_model_t), intent(inout) :: self
      real(dp), intent(in) :: q(:), v(:), h
      real(dp), intent(out) :: out
      integer, intent(inout) :: stat
    end subroutine ld_dh
  end interface

contains

  !> hess(i, j) = d2 L_d / dq_i dv_j (n x n). Serves both directions: dD1/dv = hess, dD2/dq = hess^T.
  subroutine not_provided_hessian(self, q, v, h, hess, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    hess = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_hessian

  !> omega(:, mu) = components of the one-form omega^mu at q (n x m).
  subroutine not_provided_forms(self, q, omega, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    omega = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_forms

  !> The discrete constraint omega_d(base, other, h) in R^m; the (+) scheme imposes
  !> omega_d(q_k, q_k+1, h) = 0, the (-) scheme omega_d(q_k+1, q_k, h) = 0.
  subroutine not_provided_dconstraint(self, base, other, h, out, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_dconstraint

  !> Gap functions g(j) = g_j(q); the admissible set is {q : g_j(q) >= 0 for all j}.
  subroutine not_provided_gaps(self, q, g, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_gaps

  !> dg(:, j) = gradient of g_j at q (n x n_gaps).
  subroutine not_provided_gap_grads(self, q, dg, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_gap_grads

  !> A step-independent energy H(q, p), normally the Hamiltonian; needed only for the
  !> 'hamiltonian' impact condition.
  subroutine not_provided_energy(self, q, p, e, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.0_dp
    stat = VCI_NOT_PROVIDED
  end subroutine not_provided_energy
end module vci_model
