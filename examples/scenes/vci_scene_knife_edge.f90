!> A knife edge between two walls (issue 25's second nonholonomic scene): a blade in the plane,
!> q = (x, y, theta), that cannot slip sideways, sin(theta) x' - cos(theta) y' = 0 (a non-integrable
!> constraint), between the walls x = -wall and x = wall; L = m (x'^2 + y'^2)/2 + I theta'^2/2, no
!> potential. Between impacts theta = theta0 + w t and the blade point runs on a circle of radius v/w
!> at constant speed v; at a wall the speed along the blade reverses (v -> -v, w unchanged).
!> A continuous model (the library discretises it by the scheme chosen at run time), with its exact
!> solution (`knife_exact`: closed form, or RK4 of the same motion as a second construction), shared
!> by examples/knife_edge.f90, test/core/test_nonholo.pf and bench/lobatto_nonholo_corridor.f90.
module vci_scene_knife_edge
  use vci, only: dp, i8, vci_lagrangian_t, vci_observer_t, vci_impact_t
  implicit none
  private

  !> The knife between the walls x = +-wall: m = 1, I = 0.5 by default.
  type, extends(vci_lagrangian_t), public :: knife_walls_t
    real(dp) :: mass = 1.0_dp, inertia = 0.5_dp, wall = 0.4_dp
  contains
    procedure :: lagrangian => kw_l, dl_dq => kw_lq, dl_dv => kw_lv, hessians => kw_hess
    procedure :: constraint_forms => kw_forms, gaps => kw_gaps, gap_gradients => kw_ggrad, energy => kw_energy
  end type knife_walls_t

  !> A start of the knife: from the origin at angle th0, speed v along the blade, spin w, walls at
  !> x = +-wall.
  type, public :: knife_scene_t
    real(dp) :: v, w, th0, wall
  end type knife_scene_t
  !> Slow and many impacts (the energy tests): 0.38 rad of turn between impacts on average.
  type(knife_scene_t), parameter, public :: slow_knife = knife_scene_t(1.0_dp, 0.3_dp, 0.3_dp, 0.4_dp)
  !> The order scene and the example's: 2.7 and 3.6 rad of turn between impacts, each at 76 degrees
  !> to its wall (6 impacts in 20 s).
  type(knife_scene_t), parameter, public :: turning_knife = knife_scene_t(1.0_dp, 1.0_dp, 0.6_dp, 0.8_dp)
  !> A corridor (issue 25, several impacts per step): walls at x = +-0.1, spin 4 (circle radius 0.25),
  !> 7 impacts in 2 s, 0.22 ... 0.40 s apart (0.9 ... 1.6 rad of turn), each at >= 25 degrees to its
  !> wall: steps h >= 0.3 span one or more impacts each, h <= 0.1 less than half the time between two.
  type(knife_scene_t), parameter, public :: corridor_knife = knife_scene_t(1.0_dp, 4.0_dp, 0.3_dp, 0.1_dp)

  !> Watches a run: the impact times and the largest constraint residual at the step ends
  !> (knife_constraint_residual), for the example's comparison with knife_exact.
  type, extends(vci_observer_t), public :: knife_tracker_t
    real(dp), allocatable :: times(:)          !< impact times, the first `nimp` entries
    integer :: nimp = 0
    real(dp) :: worst_residual = 0.0_dp
  contains
    procedure :: on_step => tracker_step
    procedure :: on_impact => tracker_impact
  end type knife_tracker_t

  public :: knife_model, knife_start, knife_exact, knife_constraint_residual

contains

  !> The knife of scene sc as a model (n = 3, one constraint, two walls).
  function knife_model(sc) result(model)
    type(knife_scene_t), intent(in) :: sc
    type(knife_walls_t) :: model
    model%n = 3; model%m = 1; model%n_gaps = 2; model%wall = sc%wall
  end function knife_model

  !> The exact start of scene sc at t = 0: q(0) and p(0) = dL/dqdot(q(0), qdot(0)).
  subroutine knife_start(model, sc, q0, p0)
    type(knife_walls_t), intent(in) :: model
    type(knife_scene_t), intent(in) :: sc
    real(dp), intent(out) :: q0(3), p0(3)
    q0 = [0.0_dp, 0.0_dp, sc%th0]
    p0 = [model%mass * sc%v * cos(sc%th0), model%mass * sc%v * sin(sc%th0), model%inertia * sc%w]
  end subroutine knife_start

  !> |Omega(q)^T qdot| / |qdot| with qdot = M^-1 p: the constraint's relative residual at (q, p)
  !> (x and y share the mass, so p's (x, y) part is along qdot's).
  pure real(dp) function knife_constraint_residual(q, p) result(r)
    real(dp), intent(in) :: q(:), p(:)
    r = abs(sin(q(3)) * p(1) - cos(q(3)) * p(2)) / max(norm2(p(1:2)), tiny(1.0_dp))
  end function knife_constraint_residual

  subroutine tracker_step(self, step, t, q, p, lambda, energy, stat)
    class(knife_tracker_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    self%worst_residual = max(self%worst_residual, knife_constraint_residual(q, p))
  end subroutine tracker_step

  subroutine tracker_impact(self, impact, stat)
    class(knife_tracker_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    real(dp), allocatable :: grown(:)
    if (.not. allocated(self%times)) allocate (self%times(64))
    if (self%nimp == size(self%times)) then
      allocate (grown(2 * size(self%times)))
      grown(1:self%nimp) = self%times
      call move_alloc(grown, self%times)
    end if
    self%nimp = self%nimp + 1
    self%times(self%nimp) = impact%t
  end subroutine tracker_impact

  subroutine kw_l(self, q, v, l, stat)
    class(knife_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * self%mass * (v(1)**2 + v(2)**2) + 0.5_dp * self%inertia * v(3)**2
  end subroutine kw_l
  subroutine kw_lq(self, q, v, out, stat)
    class(knife_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = 0.0_dp
  end subroutine kw_lq
  subroutine kw_lv(self, q, v, out, stat)
    class(knife_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = [self%mass * v(1), self%mass * v(2), self%inertia * v(3)]
  end subroutine kw_lv
  subroutine kw_hess(self, q, v, lqq, lqv, lvv, stat)
    class(knife_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    lvv(1, 1) = self%mass; lvv(2, 2) = self%mass; lvv(3, 3) = self%inertia
  end subroutine kw_hess
  subroutine kw_forms(self, q, omega, stat)
    class(knife_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    omega(:, 1) = [sin(q(3)), -cos(q(3)), 0.0_dp]
  end subroutine kw_forms
  subroutine kw_gaps(self, q, g, stat)
    class(knife_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g = [self%wall + q(1), self%wall - q(1)]
  end subroutine kw_gaps
  subroutine kw_ggrad(self, q, dg, stat)
    class(knife_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = [1.0_dp, 0.0_dp, 0.0_dp]; dg(:, 2) = [-1.0_dp, 0.0_dp, 0.0_dp]
  end subroutine kw_ggrad
  subroutine kw_energy(self, q, p, e, stat)
    class(knife_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * (p(1)**2 + p(2)**2) / self%mass + 0.5_dp * p(3)**2 / self%inertia
  end subroutine kw_energy

  !> The knife between the walls, exact: between impacts theta = theta0 + w t and the blade point runs
  !> on a circle, x = x0 + (v/w)(sin theta - sin theta0), y = y0 - (v/w)(cos theta - cos theta0); at
  !> |x| = wall the speed along the blade reverses (v -> -v, w unchanged: the impulse has no theta part
  !> and the constraint leaves -v as the only other speed of the same energy). Impact times: first sign
  !> change of wall - |x| on a grid of 1e-3, then bisection to round-off. `rk4` > 0: the second
  !> construction, the ODE x' = v cos theta, y' = v sin theta, theta' = w by RK4 with that step, the
  !> crossing found by bisection on the length of the last RK4 step. `times` holds the first
  !> size(times) impact times, `nimp` counts them all. `angles`: each impact's angle between the
  !> velocity and its wall, asin(|cos theta|), in degrees (90: head on, 0: grazing). `speed`: the
  !> signed speed along the blade at t_end (qdot = speed (cos theta, sin theta), theta' = w).
  subroutine knife_exact(sc, t_end, rk4, q, times, nimp, angles, speed)
    type(knife_scene_t), intent(in) :: sc
    real(dp), intent(in) :: t_end, rk4
    real(dp), intent(out) :: q(3), times(:)
    integer, intent(out) :: nimp
    real(dp), intent(out), optional :: angles(:), speed
    real(dp), parameter :: deg = 180.0_dp / acos(-1.0_dp)
    real(dp) :: t, v, s0(3), tau, lo, hi, mid, st(3), w, wall
    integer :: k
    w = sc%w; wall = sc%wall
    s0 = [0.0_dp, 0.0_dp, sc%th0]; v = sc%v; t = 0.0_dp; nimp = 0
    do
      ! the next crossing from s0 (leaving a wall: start the search past it)
      lo = 0.0_dp; hi = -1.0_dp
      do k = 1, nint((t_end - t) / 1.0e-3_dp) + 1
        tau = min(k * 1.0e-3_dp, t_end - t)
        st = flow(s0, v, tau)
        if (abs(st(1)) > wall) then
          hi = tau; exit
        end if
        lo = tau
        if (tau >= t_end - t) exit
      end do
      if (hi < 0.0_dp) then
        q = flow(s0, v, t_end - t)
        if (present(speed)) speed = v
        return
      end if
      do k = 1, 200
        mid = 0.5_dp * (lo + hi)
        if (mid <= lo .or. mid >= hi) exit
        st = flow(s0, v, mid)
        if (abs(st(1)) > wall) then
          hi = mid
        else
          lo = mid
        end if
      end do
      st = flow(s0, v, lo)
      nimp = nimp + 1
      if (nimp <= size(times)) times(nimp) = t + lo
      if (present(angles)) then
        if (nimp <= size(angles)) angles(nimp) = asin(min(1.0_dp, abs(cos(st(3))))) * deg
      end if
      t = t + lo; s0 = st; s0(1) = sign(wall, st(1)); v = -v
    end do
  contains
    function flow(s, vv, tt) result(r)
      real(dp), intent(in) :: s(3), vv, tt
      real(dp) :: r(3), y(3), k1(3), k2(3), k3(3), k4(3), dt
      integer :: i, nst
      if (rk4 <= 0.0_dp) then
        r(3) = s(3) + w * tt
        r(1) = s(1) + (vv / w) * (sin(r(3)) - sin(s(3)))
        r(2) = s(2) - (vv / w) * (cos(r(3)) - cos(s(3)))
        return
      end if
      nst = max(1, ceiling(tt / rk4)); dt = tt / nst; y = s
      do i = 1, nst
        k1 = f(y, vv); k2 = f(y + 0.5_dp * dt * k1, vv); k3 = f(y + 0.5_dp * dt * k2, vv); k4 = f(y + dt * k3, vv)
        y = y + dt / 6.0_dp * (k1 + 2.0_dp * k2 + 2.0_dp * k3 + k4)
      end do
      r = y
    end function flow
    function f(y, vv) result(d)
      real(dp), intent(in) :: y(3), vv
      real(dp) :: d(3)
      d = [vv * cos(y(3)), vv * sin(y(3)), w]
    end function f
  end subroutine knife_exact
end module vci_scene_knife_edge
