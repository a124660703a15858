!> A point mass in the plane with gravity, an optional stiff vertical spring and flat walls
!> g_j(q) = normal_j . q - offset_j >= 0; midpoint discrete Lagrangian
!> L_d(q, v, h) = h [ m |v - q|^2 / (2 h^2) - V((q + v)/2) ],  V(q) = m g y + k/2 (y - y_rest)^2.
!> Used for the bouncing particle (one floor), the particle in a box (four walls, g = 0) and the
!> stiff and extreme-magnitude stability cases.
!> `particle_lagrangian_t`: the same particle as a continuous model, L = m|v|²/2 − V(q).
module vci_scene_particle
  use vci, only: dp, vci_model_t, vci_lagrangian_t
  implicit none
  private

  type, extends(vci_model_t), public :: particle_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp
    real(dp) :: k = 0.0_dp, y_rest = 0.0_dp       !< vertical spring (stiff cases)
    real(dp), allocatable :: normal(:, :), offset(:)  !< walls: normal(:, j) . q >= offset(j)
    logical :: analytic_hessian = .true.
  contains
    procedure :: d1, d2, d3, mixed_hessian, gaps, gap_gradients, energy
  end type particle_t

  type, extends(vci_lagrangian_t), public :: particle_lagrangian_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp
    real(dp), allocatable :: normal(:, :), offset(:)
  contains
    procedure :: lagrangian => pl_lagrangian, dl_dq => pl_dl_dq, dl_dv => pl_dl_dv, hessians => pl_hessians
    procedure :: gaps => pl_gaps, gap_gradients => pl_gap_grads, energy => pl_energy
  end type particle_lagrangian_t

  public :: particle_on_floor, particle_in_box, particle_lagrangian_on_floor

contains

  !> The paper's bouncing particle: floor y >= 0.
  function particle_on_floor(mass, grav) result(model)
    real(dp), intent(in) :: mass, grav
    type(particle_t) :: model
    model%n = 2; model%n_gaps = 1
    model%mass = mass; model%grav = grav
    allocate (model%normal(2, 1), model%offset(1))
    model%normal = reshape([0.0_dp, 1.0_dp], [2, 1])
    model%offset = [0.0_dp]
  end function particle_on_floor

  !> No gravity, walls x = 0, x = width, y = 0, y = height.
  function particle_in_box(width, height) result(model)
    real(dp), intent(in) :: width, height
    type(particle_t) :: model
    model%n = 2; model%n_gaps = 4; model%grav = 0.0_dp
    allocate (model%normal(2, 4), model%offset(4))
    model%normal = reshape([1.0_dp, 0.0_dp, -1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, -1.0_dp], [2, 4])
    model%offset = [0.0_dp, -width, 0.0_dp, -height]
  end function particle_in_box

  !> The bouncing particle as a continuous model: floor y >= 0.
  function particle_lagrangian_on_floor(mass, grav) result(model)
    real(dp), intent(in) :: mass, grav
    type(particle_lagrangian_t) :: model
    model%n = 2; model%n_gaps = 1
    model%mass = mass; model%grav = grav
    allocate (model%normal(2, 1), model%offset(1))
    model%normal = reshape([0.0_dp, 1.0_dp], [2, 1])
    model%offset = [0.0_dp]
  end function particle_lagrangian_on_floor

  pure real(dp) function dvdy(self, y)
    class(particle_t), intent(in) :: self
    real(dp), intent(in) :: y
    dvdy = self%mass * self%grav + self%k * (y - self%y_rest)
  end function dvdy

  subroutine d1(self, q, v, h, out, stat)
    class(particle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = -self%mass * (v - q) / h
    out(2) = out(2) - 0.5_dp * h * dvdy(self, 0.5_dp * (q(2) + v(2)))
  end subroutine d1

  subroutine d2(self, q, v, h, out, stat)
    class(particle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = self%mass * (v - q) / h
    out(2) = out(2) - 0.5_dp * h * dvdy(self, 0.5_dp * (q(2) + v(2)))
  end subroutine d2

  subroutine d3(self, q, v, h, out, stat)
    class(particle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    real(dp) :: ym
    ym = 0.5_dp * (q(2) + v(2))
    out = -0.5_dp * self%mass * sum((v - q)**2) / h**2 &
          - (self%mass * self%grav * ym + 0.5_dp * self%k * (ym - self%y_rest)**2)
  end subroutine d3

  subroutine mixed_hessian(self, q, v, h, hess, stat)
    class(particle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    if (.not. self%analytic_hessian) then   ! let the library difference it (tests and benchmarks)
      call self%not_provided(stat); return
    end if
    hess = 0.0_dp
    hess(1, 1) = -self%mass / h
    hess(2, 2) = -self%mass / h - 0.25_dp * h * self%k
  end subroutine mixed_hessian

  subroutine gaps(self, q, g, stat)
    class(particle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g = matmul(q, self%normal) - self%offset
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(particle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg = self%normal
  end subroutine gap_gradients

  subroutine energy(self, q, p, e, stat)
    class(particle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * sum(p**2) / self%mass + self%mass * self%grav * q(2) + 0.5_dp * self%k * (q(2) - self%y_rest)**2
  end subroutine energy
  subroutine pl_lagrangian(self, q, v, l, stat)
    class(particle_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * self%mass * sum(v**2) - self%mass * self%grav * q(2)
  end subroutine pl_lagrangian

  subroutine pl_dl_dq(self, q, v, out, stat)
    class(particle_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = [0.0_dp, -self%mass * self%grav]
  end subroutine pl_dl_dq

  subroutine pl_dl_dv(self, q, v, out, stat)
    class(particle_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = self%mass * v
  end subroutine pl_dl_dv

  !> Constant blocks: L_qq = L_qv = 0, L_vv = m I.
  subroutine pl_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(particle_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    lvv(1, 1) = self%mass; lvv(2, 2) = self%mass
  end subroutine pl_hessians

  subroutine pl_gaps(self, q, g, stat)
    class(particle_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g = matmul(q, self%normal) - self%offset
  end subroutine pl_gaps

  subroutine pl_gap_grads(self, q, dg, stat)
    class(particle_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg = self%normal
  end subroutine pl_gap_grads

  subroutine pl_energy(self, q, p, e, stat)
    class(particle_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * sum(p**2) / self%mass + self%mass * self%grav * q(2)
  end subroutine pl_energy
end module vci_scene_particle
