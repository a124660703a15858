!> Extra models for the stability cases (docs/STABILITY.md): a planar particle with one massless
!> coordinate, so that the n x n block dD1/dv of the Newton matrix is singular.
!>
!> q = (x, y, z); L_d(q, v, h) = h [ m |(v_xy - q_xy)/h|^2 / 2 - m g (q_y + v_y)/2 ]: z carries no
!> kinetic energy. With `tied` the nonholonomic form omega = dz - dx (discrete: ((v_z - q_z) -
!> (v_x - q_x))/h = 0) makes z follow x and the augmented Newton matrix regular (the situation of the
!> pendulum at theta = pi, docs/DESIGN.md §8); without it z is undetermined and the matrix is singular.
!> Floor y >= 0.
module vci_stab_models
  use vci_kinds, only: dp
  use vci_model, only: vci_model_t
  implicit none
  private

  type, extends(vci_model_t), public :: massless_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp
  contains
    procedure :: d1 => ml_d1, d2 => ml_d2, d3 => ml_d3, mixed_hessian => ml_hessian
    procedure :: constraint_forms => ml_forms, discrete_constraint => ml_dconstraint
    procedure :: gaps => ml_gaps, gap_gradients => ml_gap_gradients, energy => ml_energy
  end type massless_t

  public :: massless_model

contains

  !> tied: add the constraint z' = x' (m = 1); otherwise m = 0 and z is free and massless.
  function massless_model(tied) result(model)
    logical, intent(in) :: tied
    type(massless_t) :: model
    model%n = 3; model%n_gaps = 1
    model%m = merge(1, 0, tied)
  end function massless_model

  subroutine ml_d1(self, q, v, h, out, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1:2) = -self%mass * (v(1:2) - q(1:2)) / h
    out(2) = out(2) - 0.5_dp * h * self%mass * self%grav
    out(3) = 0.0_dp
  end subroutine ml_d1

  subroutine ml_d2(self, q, v, h, out, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1:2) = self%mass * (v(1:2) - q(1:2)) / h
    out(2) = out(2) - 0.5_dp * h * self%mass * self%grav
    out(3) = 0.0_dp
  end subroutine ml_d2

  subroutine ml_d3(self, q, v, h, out, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    out = -0.5_dp * self%mass * sum((v(1:2) - q(1:2))**2) / h**2 - 0.5_dp * self%mass * self%grav * (q(2) + v(2))
  end subroutine ml_d3

  subroutine ml_hessian(self, q, v, h, hess, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    hess = 0.0_dp
    hess(1, 1) = -self%mass / h
    hess(2, 2) = -self%mass / h   ! hess(3, 3) = 0: the singular block
  end subroutine ml_hessian

  subroutine ml_forms(self, q, omega, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    omega(:, 1) = [-1.0_dp, 0.0_dp, 1.0_dp]
  end subroutine ml_forms

  subroutine ml_dconstraint(self, base, other, h, out, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = ((other(3) - base(3)) - (other(1) - base(1))) / h
  end subroutine ml_dconstraint

  subroutine ml_gaps(self, q, g, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = q(2)
  end subroutine ml_gaps

  subroutine ml_gap_gradients(self, q, dg, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = [0.0_dp, 1.0_dp, 0.0_dp]
  end subroutine ml_gap_gradients

  subroutine ml_energy(self, q, p, e, stat)
    class(massless_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * (p(1)**2 + p(2)**2) / self%mass + self%mass * self%grav * q(2)
  end subroutine ml_energy
end module vci_stab_models
