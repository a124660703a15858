!> A planar pendulum between two walls (an impact oscillator) as a user-written discrete
!> Lagrangian: q = theta from the downward vertical, L = m l^2 thetadot^2 / 2 + m g l cos theta,
!> midpoint L_d(q, v, h) = h [ m l^2 ((v - q)/h)^2 / 2 + m g l cos((q + v)/2) ], walls
!> g_1 = theta_w - theta >= 0, g_2 = theta + theta_w >= 0 (elastic impact thetadot -> -thetadot).
!> Free flight is nonlinear (theta'' = -(g/l) sin theta), so no fixed-step method is exact.
!> Exact reference: test/support/vci_ref_pendulum_walls.f90. Used by tools/results.
module vci_scene_pendulum_walls_ld
  use vci, only: dp, vci_model_t
  use vci_scene_pendulum_walls, only: pendulum_walls_gaps, pendulum_walls_gap_gradients, pendulum_energy
  implicit none
  private

  type, extends(vci_model_t), public :: pendulum_walls_ld_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, length = 1.0_dp, theta_wall = 1.0_dp
  contains
    procedure :: d1, d2, d3, mixed_hessian, gaps, gap_gradients, energy
  end type pendulum_walls_ld_t

  public :: pendulum_walls_ld_model

contains

  !> m = 1, g = 9.8, l = 1 and walls at +-theta_wall.
  function pendulum_walls_ld_model(theta_wall) result(model)
    real(dp), intent(in) :: theta_wall
    type(pendulum_walls_ld_t) :: model
    model%n = 1; model%n_gaps = 2
    model%theta_wall = theta_wall
  end function pendulum_walls_ld_model

  subroutine d1(self, q, v, h, out, stat)
    class(pendulum_walls_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = -self%mass * self%length**2 * (v(1) - q(1)) / h &
             - 0.5_dp * h * self%mass * self%grav * self%length * sin(0.5_dp * (q(1) + v(1)))
  end subroutine d1

  subroutine d2(self, q, v, h, out, stat)
    class(pendulum_walls_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = self%mass * self%length**2 * (v(1) - q(1)) / h &
             - 0.5_dp * h * self%mass * self%grav * self%length * sin(0.5_dp * (q(1) + v(1)))
  end subroutine d2

  subroutine d3(self, q, v, h, out, stat)
    class(pendulum_walls_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    out = -0.5_dp * self%mass * self%length**2 * (v(1) - q(1))**2 / h**2 &
          + self%mass * self%grav * self%length * cos(0.5_dp * (q(1) + v(1)))
  end subroutine d3

  subroutine mixed_hessian(self, q, v, h, hess, stat)
    class(pendulum_walls_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    hess(1, 1) = -self%mass * self%length**2 / h &
                 - 0.25_dp * h * self%mass * self%grav * self%length * cos(0.5_dp * (q(1) + v(1)))
  end subroutine mixed_hessian

  subroutine gaps(self, q, g, stat)
    class(pendulum_walls_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call pendulum_walls_gaps(self%theta_wall, q, g)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(pendulum_walls_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call pendulum_walls_gap_gradients(dg)
  end subroutine gap_gradients

  !> H(q, p) = p^2 / (2 m l^2) - m g l cos q.
  subroutine energy(self, q, p, e, stat)
    class(pendulum_walls_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = pendulum_energy(self%mass, self%grav, self%length, q, p)
  end subroutine energy
end module vci_scene_pendulum_walls_ld
