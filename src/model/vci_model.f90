!> The abstract discrete model a user extends: a discrete Lagrangian L_d(q, v, h) and, only when the
!> scene needs them, nonholonomic constraints, walls (gap functions) and analytic Jacobians. (A user
!> who knows the continuous L(q, qdot) instead extends `vci_lagrangian_t` and picks a scheme.)
!>
!> Required: d1, d2, d3 (partials of L_d). Everything else has a default that tells the library
!> "not provided" (`call self%not_provided(stat)`, vci_model_base); the library then either does without it (m = 0:
!> no multipliers; n_gaps = 0: no impact detection) or differences it (mixed Hessian, discrete
!> constraint Jacobian, gap gradients).
!> Sizes, constraint forms, gaps and energy come from `vci_model_base_t`.
!>
!> Every procedure receives `stat` preset to 0. The callback contract (as SUNDIALS'): leave it 0 on
!> success; set it > 0 for a recoverable failure (at a trial point of Newton's line search the
!> solver backs off to a shorter step; anywhere else the step fails with VCI_ERR_CALLBACK); set it
!> < 0 for an unrecoverable one (the step fails at once with VCI_ERR_CALLBACK). NaN or Inf outputs
!> count as recoverable failures (VCI_ERR_NONFINITE if they end the step). Never stop the program
!> from a callback.
module vci_model
  use vci_kinds, only: dp
  use vci_model_base, only: vci_model_base_t
  implicit none
  private

  !> A model given by its discrete Lagrangian L_d(q, v, h): extend it and write d1, d2, d3.
  type, abstract, extends(vci_model_base_t), public :: vci_model_t
  contains
    !> D1 L_d(q, v, h) in R^n
    procedure(ld_partial), deferred :: d1
    !> D2 L_d(q, v, h) in R^n
    procedure(ld_partial), deferred :: d2
    !> D3 L_d(q, v, h) = dL_d/dh; E_d = -D3 L_d
    procedure(ld_dh), deferred :: d3
    !> d2 L_d/dq dv (n x n); optional, else differenced
    procedure :: mixed_hessian => not_provided_hessian
    !> omega_d(base, other, h) in R^m, the discrete constraint; required when m > 0
    procedure :: discrete_constraint => not_provided_dconstraint
    !> d omega_d / d other (m x n); optional, else differenced
    procedure :: discrete_constraint_jacobian => not_provided_dconstraint_jacobian
    !> D1, D2, D3 L_d and the mixed Hessian at one point in one call (optional; issue 26): the
    !> scheme then asks for nothing else of L_d, so shared work (sines, cosines) is done once
    procedure :: ld_fused => not_provided_fused
  end type vci_model_t

  abstract interface
    !> out = a partial of L_d at (q, v, h) in R^n (d1: D1 L_d, d2: D2 L_d).
    subroutine ld_partial(self, q, v, h, out, stat)
      import :: vci_model_t, dp
      class(vci_model_t), intent(inout) :: self
      real(dp), intent(in) :: q(:), v(:), h
      real(dp), intent(out) :: out(:)
      integer, intent(inout) :: stat
    end subroutine ld_partial
    !> out = D3 L_d(q, v, h) = dL_d/dh.
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
    call self%not_provided(stat)
  end subroutine not_provided_hessian

  !> The discrete constraint omega_d(base, other, h) in R^m; the (+) scheme imposes
  !> omega_d(q_k, q_k+1, h) = 0, the (-) scheme omega_d(q_k+1, q_k, h) = 0.
  subroutine not_provided_dconstraint(self, base, other, h, out, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_dconstraint

  !> The discrete constraint's Jacobian along its second argument: jac(mu, i) = d omega_d^mu / d other_i
  !> at (base, other, h), m x n (both directions impose omega_d(known, unknown)). Optional: without it
  !> the library differences omega_d (2n extra evaluations per Newton matrix).
  subroutine not_provided_dconstraint_jacobian(self, base, other, h, jac, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: jac(:, :)
    integer, intent(inout) :: stat
    jac = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_dconstraint_jacobian

  !> Everything a Newton iteration of a sub-step needs of L_d at (q, v, h), in one call:
  !> d1 = D1 L_d, d2 = D2 L_d (R^n), d3 = D3 L_d = dL_d/dh, hess(i, j) = d2 L_d / dq_i dv_j (n x n),
  !> the same values d1, d2, d3 and mixed_hessian return (bit for bit when the arithmetic is the
  !> same: the trajectories then are). Optional: a model that overrides it must also supply a
  !> Hessian here (it replaces mixed_hessian in the solves); the separate procedures stay required
  !> (the model checker and the probes call them). The scheme keeps the last point's values, so a
  !> residual, the Jacobian and the new momentum at one point cost one call.
  subroutine not_provided_fused(self, q, v, h, d1, d2, d3, hess, stat)
    class(vci_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: d1(:), d2(:), d3, hess(:, :)
    integer, intent(inout) :: stat
    d1 = 0.0_dp; d2 = 0.0_dp; d3 = 0.0_dp; hess = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_fused
end module vci_model
