!> A planar pendulum swinging between two walls (an impact oscillator): q = theta from the downward
!> vertical, L = ½ m l² θ̇² + m g l cos θ (so θ̈ = −(g/l) sin θ in free flight), walls
!> g_1 = θ_w − θ >= 0 and g_2 = θ + θ_w >= 0 with elastic impacts θ̇ → −θ̇. With walls = .false.
!> it is the free pendulum (a smooth nonlinear scene for order measurements). A continuous model:
!> the library discretises it by the scheme chosen at run time.
module vci_scene_pendulum_walls
  use vci, only: dp, vci_lagrangian_t
  implicit none
  private

  type, extends(vci_lagrangian_t), public :: pendulum_walls_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, length = 1.0_dp, theta_wall = 1.0_dp
  contains
    procedure :: lagrangian, dl_dq, dl_dv, hessians, gaps, gap_gradients, energy
  end type pendulum_walls_t

  public :: pendulum_walls_model
  ! the walls and H, shared with the hand-written midpoint L_d (vci_scene_pendulum_walls_ld)
  public :: pendulum_walls_gaps, pendulum_walls_gap_gradients, pendulum_energy

contains

  !> Defaults: m = 1, g = 9.8, l = 1, walls at +-1 rad (walls = .false.: no walls).
  function pendulum_walls_model(walls) result(model)
    logical, intent(in) :: walls
    type(pendulum_walls_t) :: model
    model%n = 1
    model%n_gaps = merge(2, 0, walls)
  end function pendulum_walls_model

  subroutine lagrangian(self, q, v, l, stat)
    class(pendulum_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * self%mass * self%length**2 * v(1)**2 + self%mass * self%grav * self%length * cos(q(1))
  end subroutine lagrangian

  subroutine dl_dq(self, q, v, out, stat)
    class(pendulum_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = -self%mass * self%grav * self%length * sin(q(1))
  end subroutine dl_dq

  subroutine dl_dv(self, q, v, out, stat)
    class(pendulum_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = self%mass * self%length**2 * v(1)
  end subroutine dl_dv

  subroutine hessians(self, q, v, lqq, lqv, lvv, stat)
    class(pendulum_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    lqq(1, 1) = -self%mass * self%grav * self%length * cos(q(1))
    lqv(1, 1) = 0.0_dp
    lvv(1, 1) = self%mass * self%length**2
  end subroutine hessians

  subroutine gaps(self, q, g, stat)
    class(pendulum_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call pendulum_walls_gaps(self%theta_wall, q, g)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(pendulum_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call pendulum_walls_gap_gradients(dg)
  end subroutine gap_gradients

  !> H(q, p) (pendulum_energy).
  subroutine energy(self, q, p, e, stat)
    class(pendulum_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = pendulum_energy(self%mass, self%grav, self%length, q, p)
  end subroutine energy

  !> The walls g_1 = θ_w − θ >= 0 and g_2 = θ + θ_w >= 0.
  pure subroutine pendulum_walls_gaps(theta_wall, q, g)
    real(dp), intent(in) :: theta_wall, q(:)
    real(dp), intent(out) :: g(:)
    g(1) = theta_wall - q(1)
    g(2) = q(1) + theta_wall
  end subroutine pendulum_walls_gaps

  !> Their gradients (columns): −1 and +1.
  pure subroutine pendulum_walls_gap_gradients(dg)
    real(dp), intent(out) :: dg(:, :)
    dg(1, 1) = -1.0_dp
    dg(1, 2) = 1.0_dp
  end subroutine pendulum_walls_gap_gradients

  !> H(q, p) = p²/(2 m l²) − m g l cos θ.
  pure real(dp) function pendulum_energy(mass, grav, length, q, p) result(e)
    real(dp), intent(in) :: mass, grav, length, q(:), p(:)
    e = 0.5_dp * p(1)**2 / (mass * length**2) - mass * grav * length * cos(q(1))
  end function pendulum_energy
end module vci_scene_pendulum_walls
