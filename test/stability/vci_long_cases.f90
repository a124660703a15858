!> Long steps (issue 27): the scenes whose long steps used to end runs, each with an exact or
!> independent reference, run at one step length with the safety net on or off (set_step_splits).
!> Shared by test_stab_long_steps.pf and tools/stability/vci_long_steps_table.f90, so the tests and
!> the table of docs/STABILITY.md ("Long steps") see the same numbers.
!>
!> Scenes:
!> - LONG_PENDULUM: the walled pendulum of examples/pendulum_walls (theta'' = -9.8 sin theta,
!>   walls at |theta| = 1, theta(0) = 0, theta'(0) = 4) to t = 10; exact reference
!>   vci_ref_pendulum_walls (Jacobi elliptic functions, quad precision; without walls the free
!>   pendulum librates, turning at 1.385 rad).
!> - LONG_KEPLER_CIRCLE: Kepler (L = |v|^2/2 + 1/|q|, a = 1, e = 0.5, from pericentre) inside the
!>   circle |q| <= 1.2 centred on the attracting centre, to t = 20; exact reference in closed form
!>   (kepler_circle_exact: the reflection mirrors the orbit about the line through the impact).
!> - LONG_KEPLER_WALL: the same orbit's start below the straight wall q2 <= kepler_wall_w (not
!>   through the centre: every impact changes the orbit), to t = 20; reference in closed form
!>   (vci_kepler_wall: Kepler's equation between impacts, the wall crossing solved in the
!>   eccentric anomaly; checked against quad-precision RK4 in test_kepler_wall_reference).
!> - LONG_FPU: the FPU-beta chain between walls (n = 32, beta = 1, |x_i| <= 0.6, the start of
!>   tools/results) to t = 2; reference: the quad-precision event-driven Taylor method
!>   (test/support/vci_ref_fpu_walls.f90, step 0.01).
!> - LONG_KNIFE: the turning knife edge between the walls x = +-0.8 (examples/knife_edge; one
!>   nonholonomic constraint, 6 impacts in 20 s, 2.7 and 3.6 rad of turn between them) to t = 20;
!>   closed-form reference knife_exact (vci_scene_knife_edge; without walls the blade runs on a
!>   circle of radius 1).
!> - LONG_NH_PENDULUM: the paper's nonholonomic pendulum in a cylinder (examples/pendulum, docs/DESIGN.md
!>   §8; constraint phi' = f(theta) theta', 3 impacts in 5 s) to t = 5 from the exact (q(0), p(0));
!>   reference vci_ref_pendulum (order-8 Gauss-Legendre on the reduced 1-DOF equation; without
!>   walls the same equation with the cylinder out of reach).
module vci_long_cases
  use vci
  use vci_test_kepler, only: kepler_t, kepler_exact
  use vci_scene_pendulum_walls, only: pendulum_walls_model
  use vci_scene_fpu_walls, only: fpu_walls_lagrangian_model
  use vci_ref_pendulum_walls, only: pendulum_walls_params, pendulum_walls_exact
  use vci_kepler_wall, only: kepler_wall_t, kepler_wall_exact
  use vci_ref_fpu_walls, only: fpu_walls_params, fpu_walls_run
  use vci_scene_knife_edge, only: knife_walls_t, knife_scene_t, knife_model, knife_start, knife_exact, turning_knife
  use vci_scene_pendulum, only: pendulum_lagrangian_model, pendulum_f
  use vci_ref_pendulum, only: pendulum_params, pendulum_exact
  implicit none
  private

  integer, parameter, public :: LONG_PENDULUM = 1, LONG_KEPLER_CIRCLE = 2, LONG_FPU = 3, LONG_KEPLER_WALL = 4, &
                                LONG_KNIFE = 5, LONG_NH_PENDULUM = 6
  integer, parameter, public :: LONG_SCENES = 6
  character(len=24), parameter, public :: long_scene_name(LONG_SCENES) = &
    [character(len=24) :: 'walled pendulum', 'Kepler in a circle', 'FPU chain n = 32', 'Kepler below a wall', &
     'knife between walls', 'paper''s pendulum']
  real(dp), parameter, public :: long_t_final(LONG_SCENES) = [10.0_dp, 20.0_dp, 2.0_dp, 20.0_dp, 20.0_dp, 5.0_dp]
  !> The straight wall's height in LONG_KEPLER_WALL.
  real(dp), parameter, public :: kepler_wall_w = 0.1_dp

  real(dp), parameter :: kepler_e = 0.5_dp, kepler_radius = 1.2_dp
  integer, parameter :: fpu_n = 32
  real(dp), parameter :: fpu_beta = 1.0_dp, fpu_w = 0.6_dp

  !> Kepler's problem inside a circle |q| <= radius centred on the attracting centre.
  type, extends(kepler_t), public :: kepler_circle_t
    real(dp) :: radius = kepler_radius
  contains
    procedure :: gaps => kc_gaps, gap_gradients => kc_gap_gradients, energy => kc_energy
  end type kepler_circle_t

  !> One run: how far it got, how often the safety net stepped in, the error at the end.
  type, public :: long_run_t
    integer :: status = VCI_OK
    character(len=VCI_MSG_LEN) :: message = ''
    integer(i8) :: steps = 0, impacts = 0, split_steps = 0, largest_split = 0
    real(dp) :: t_end = 0.0_dp
    real(dp) :: error = huge(1.0_dp)   !< max |q - q_ref|, |p - p_ref| at the end (huge: did not finish)
    !> Kepler scenes: |H(q, p) - H(q0, p0)| at the end (the walls keep H; huge: did not finish or
    !> another scene)
    real(dp) :: energy_error = huge(1.0_dp)
    !> the reference's impacts up to t_end (-1: not counted, as in the circle's closed form, or the
    !> run did not finish)
    integer :: exact_impacts = -1
  end type long_run_t

  public :: long_run, kepler_circle_exact, long_start

contains

  subroutine kc_gaps(self, q, g, stat)
    class(kepler_circle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%radius**2 - sum(q**2)
  end subroutine kc_gaps

  subroutine kc_gap_gradients(self, q, dg, stat)
    class(kepler_circle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = -2.0_dp * q
  end subroutine kc_gap_gradients

  subroutine kc_energy(self, q, p, e, stat)
    class(kepler_circle_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * sum(p**2) - 1.0_dp / norm2(q)
  end subroutine kc_energy

  !> Exact state at time t of the orbit a = 1, eccentricity e from pericentre (1 - e, 0) inside
  !> |q| <= radius (1 - e < radius < 1 + e). The orbit reaches the circle at eccentric anomaly E*
  !> (1 - e cos E* = radius), time t* = E* - e sin E*, angle phi*. The reflection reverses the radial
  !> velocity and keeps the tangential one, so the motion after it is the motion before it mirrored
  !> about the line at phi* and run backwards; back at pericentre (t = 2 t*, angle 2 phi*) it is
  !> the orbit rotated by 2 phi*. Period of the pattern 2 t*.
  subroutine kepler_circle_exact(e, radius, t, q, v)
    real(dp), intent(in) :: e, radius, t
    real(dp), intent(out) :: q(2), v(2)
    real(dp) :: ea, ts, phi, tau, rot, c, s, qs(2), vs(2), mir(2, 2)
    integer(i8) :: k
    ea = acos((1.0_dp - radius) / e)
    ts = ea - e * sin(ea)
    call kepler_exact(e, ts, qs, vs)
    phi = atan2(qs(2), qs(1))
    k = floor(t / (2.0_dp * ts), i8)
    tau = t - real(k, dp) * 2.0_dp * ts
    if (tau <= ts) then
      call kepler_exact(e, tau, q, v)
    else
      call kepler_exact(e, 2.0_dp * ts - tau, qs, vs)
      mir = reshape([cos(2.0_dp * phi), sin(2.0_dp * phi), sin(2.0_dp * phi), -cos(2.0_dp * phi)], [2, 2])
      q = matmul(mir, qs); v = -matmul(mir, vs)
    end if
    rot = 2.0_dp * phi * real(k, dp)
    c = cos(rot); s = sin(rot)
    q = [c * q(1) - s * q(2), s * q(1) + c * q(2)]
    v = [c * v(1) - s * v(2), s * v(1) + c * v(2)]
  end subroutine kepler_circle_exact

  !> Run scene from t = 0 to long_t_final(scene) (rounded to whole steps) with the scheme
  !> (VCI_SCHEME_MIDPOINT or VCI_SCHEME_LOBATTO with `stages`), step h and the safety net's bound
  !> `splits` (1: off); the other settings are the library's defaults. walls = .false.: the same
  !> scene and start without walls (the free flight, whose own stability limits the step).
  !> max_iterations: Newton's cap (default 30; a low cap forces failures for the net to catch).
  !> impact_energy: the impact condition (default the library's, VCI_IMPACT_DISCRETE).
  subroutine long_run(scene, scheme, stages, h, splits, r, walls, max_iterations, impact_energy)
    integer, intent(in) :: scene, scheme, stages, splits
    real(dp), intent(in) :: h
    type(long_run_t), intent(out) :: r
    logical, intent(in), optional :: walls
    integer, intent(in), optional :: max_iterations, impact_energy
    class(vci_lagrangian_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    type(vci_stats_t) :: stats
    type(pendulum_walls_params) :: pw
    real(dp) :: times(1), knife_times(64), speed
    type(knife_scene_t) :: knife
    type(pendulum_params) :: nh
    real(dp), allocatable :: nh_times(:)
    real(dp), allocatable :: q0(:), p0(:), qr(:), pr(:), q(:), p(:)
    integer(i8) :: k, nsteps
    integer :: stat, nimp
    real(dp) :: th, om, w, pmin, thd
    logical :: with_walls
    with_walls = .true.
    if (present(walls)) with_walls = walls
    w = fpu_w
    if (.not. with_walls) w = huge(1.0_dp)
    select case (scene)
    case (LONG_PENDULUM)
      allocate (model, source=pendulum_walls_model(with_walls))
    case (LONG_KEPLER_CIRCLE)
      if (with_walls) then
        allocate (kepler_circle_t :: model)
        model%n_gaps = 1
      else
        allocate (kepler_t :: model)
      end if
      model%n = 2
    case (LONG_KEPLER_WALL)
      if (with_walls) then
        allocate (kepler_wall_t :: model)
        select type (model)
        type is (kepler_wall_t)
          model%w = kepler_wall_w
        end select
        model%n_gaps = 1
      else
        allocate (kepler_t :: model)
      end if
      model%n = 2
    case (LONG_KNIFE)
      allocate (model, source=knife_model(turning_knife))
      if (.not. with_walls) model%n_gaps = 0
    case (LONG_NH_PENDULUM)
      allocate (model, source=pendulum_lagrangian_model())
      if (.not. with_walls) model%n_gaps = 0
    case default
      allocate (model, source=fpu_walls_lagrangian_model(fpu_n, fpu_beta, w))
    end select
    call long_start(scene, q0, p0)
    call integ%create(model, h, stat)
    if (stat == VCI_OK) call integ%set_scheme(scheme, stages, stat)
    if (stat == VCI_OK) call integ%set_step_splits(splits, stat)
    if (stat == VCI_OK .and. present(max_iterations)) call integ%set_tolerances(0.0_dp, 1.0e-12_dp, max_iterations, stat)
    if (stat == VCI_OK .and. present(impact_energy)) call integ%set_impact_energy(impact_energy, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    nsteps = nint(long_t_final(scene) / h, i8)
    if (stat == VCI_OK) then
      do k = 1, nsteps
        call integ%step(1, stat)
        if (stat /= VCI_OK) exit
      end do
    end if
    r%status = stat
    r%message = integ%message()
    stats = integ%statistics()
    r%steps = stats%steps; r%impacts = stats%impacts
    r%split_steps = stats%split_steps; r%largest_split = stats%largest_split
    r%t_end = integ%time()
    if (stat /= VCI_OK) return
    q = integ%configuration(); p = integ%momentum()
    allocate (qr(size(q)), pr(size(q)))
    select case (scene)
    case (LONG_PENDULUM)
      ! without walls: the free pendulum (it librates, turning at 1.385 rad)
      if (with_walls) pw%theta_w = 1.0_dp
      call pendulum_walls_exact(pw, q0(1), p0(1), r%t_end, th, om, nimp)
      qr = [th]; pr = [om]
      if (with_walls) r%exact_impacts = nimp
    case (LONG_KEPLER_CIRCLE)
      if (with_walls) then
        call kepler_circle_exact(kepler_e, kepler_radius, r%t_end, qr, pr)
      else
        call kepler_exact(kepler_e, r%t_end, qr, pr)
      end if
    case (LONG_KEPLER_WALL)
      if (with_walls) then
        call kepler_wall_exact(kepler_wall_w, q0, p0, r%t_end, qr, pr, nimp, times, pmin)
        r%exact_impacts = nimp
      else
        call kepler_exact(kepler_e, r%t_end, qr, pr)
      end if
    case (LONG_KNIFE)
      ! without walls: the same blade with the walls out of reach (a circle of radius v / w = 1)
      knife = turning_knife
      if (.not. with_walls) knife%wall = 1.0e30_dp
      call knife_exact(knife, r%t_end, 0.0_dp, qr, knife_times, nimp, speed=speed)
      select type (model)
      type is (knife_walls_t)
        pr = [model%mass * speed * cos(qr(3)), model%mass * speed * sin(qr(3)), model%inertia * knife%w]
      end select
      if (with_walls) r%exact_impacts = nimp
    case (LONG_NH_PENDULUM)
      ! without walls: the cylinder out of reach (R = 1e30); p = m l^2 (theta', sin^2 theta phi')
      if (.not. with_walls) nh%radius = 1.0e30_dp
      call pendulum_exact(nh, q0(1), p0(1) / (nh%m * nh%ell**2), q0(2), r%t_end, th, om, thd, nh_times, nimp)
      qr = [th, om]
      pr = nh%m * nh%ell**2 * [thd, sin(th)**2 * pendulum_f(th) * thd]
      if (with_walls) r%exact_impacts = nimp
    case default
      call fpu_walls_run(fpu_walls_params(beta=fpu_beta, w=w, step=0.01_dp), q0, p0, r%t_end, qr, pr, nimp)
      if (with_walls) r%exact_impacts = nimp
    end select
    r%error = max(maxval(abs(q - qr)), maxval(abs(p - pr)))
    if (scene == LONG_KEPLER_CIRCLE .or. scene == LONG_KEPLER_WALL) &
      r%energy_error = abs(0.5_dp * sum(p**2) - 1.0_dp / norm2(q) - (0.5_dp * sum(p0**2) - 1.0_dp / norm2(q0)))
  end subroutine long_run

  !> The start of a scene (both Kepler scenes: the pericentre of a = 1, e = 0.5; the knife: the exact
  !> (q(0), p(0)) of knife_start).
  subroutine long_start(scene, q0, p0)
    integer, intent(in) :: scene
    real(dp), allocatable, intent(out) :: q0(:), p0(:)
    real(dp) :: pi
    integer :: i
    type(knife_walls_t) :: knife
    pi = acos(-1.0_dp)
    select case (scene)
    case (LONG_PENDULUM)
      q0 = [0.0_dp]; p0 = [4.0_dp]
    case (LONG_KEPLER_CIRCLE, LONG_KEPLER_WALL)
      allocate (q0(2), p0(2))
      call kepler_exact(kepler_e, 0.0_dp, q0, p0)
    case (LONG_NH_PENDULUM)
      ! q(0) = (0.75 pi, 0), qdot(0) = (pi/4, (pi + 1/2) pi/4), p = m l^2 (theta', sin^2 theta phi')
      q0 = [0.75_dp * pi, 0.0_dp]
      p0 = 4.0_dp * [pi / 4.0_dp, sin(q0(1))**2 * (pi + 0.5_dp) * pi / 4.0_dp]
    case (LONG_KNIFE)
      allocate (q0(3), p0(3))
      knife = knife_model(turning_knife)
      call knife_start(knife, turning_knife, q0, p0)
    case default
      allocate (q0(fpu_n), p0(fpu_n))
      do i = 1, fpu_n
        q0(i) = 0.4_dp * fpu_w * sin(2 * pi * i / (fpu_n + 1))
        p0(i) = 1.2_dp * sin(3 * pi * i / (fpu_n + 1)) + 0.8_dp * sin(pi * i / (fpu_n + 1))
      end do
    end select
  end subroutine long_start
end module vci_long_cases
