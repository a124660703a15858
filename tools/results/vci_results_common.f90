!> Shared by the results drivers (vci and CVODE): the scenes' set-ups (the paper's three, docs/DESIGN.md
!> §8, plus the walled planar pendulum and the FPU-beta chain between walls), their independent
!> references (test/support/vci_ref_*.f90), the error measures and the timers.
!>
!> Error measures, the same for every method:
!>  - final error: max-norm of the configuration error at the final time (particle (x, y),
!>    ellipse (theta, x, y), pendulum (theta, phi)) against the reference at that same time;
!>  - energy error: largest |E - E0| over the run, E0 the exact energy of the initial condition;
!>  - impact-time error: for every reference impact in the horizon, the distance to the nearest
!>    impact time of the method; the largest of these (matched impacts).
module vci_results_common
  use, intrinsic :: iso_fortran_env, only: real64, int64, output_unit
  use vci_ref_particle, only: particle_exact
  use vci_ref_ellipse, only: ellipse_params, ellipse_exact, ellipse_energy
  use vci_ref_pendulum, only: pendulum_params, pendulum_exact, pendulum_energy
  use vci_ref_pendulum_walls, only: pendulum_walls_params, pendulum_walls_exact
  use vci_ref_fpu_walls, only: fpu_walls_params, fpu_walls_run
  use, intrinsic :: iso_c_binding, only: c_int, c_long
  implicit none
  private

  !> struct timespec of Linux (tv_sec, tv_nsec), for clock_gettime
  type, bind(c) :: timespec_t
    integer(c_long) :: tv_sec = 0, tv_nsec = 0
  end type timespec_t
  interface
    integer(c_int) function clock_gettime(clock_id, ts) bind(c, name='clock_gettime')
      import :: c_int, timespec_t
      integer(c_int), value :: clock_id
      type(timespec_t), intent(out) :: ts
    end function clock_gettime
  end interface
  !> Linux's CLOCK_PROCESS_CPUTIME_ID: the CPU time of every thread of the process, in nanoseconds
  integer(c_int), parameter :: CLOCK_PROCESS_CPUTIME_ID = 2

  integer, parameter, public :: rk = real64
  real(rk), parameter, public :: pi = acos(-1.0_rk)

  integer, parameter, public :: SCENE_PARTICLE = 1, SCENE_ELLIPSE = 2, SCENE_PENDULUM = 3, &
                                SCENE_PWALLS = 4, SCENE_FPU = 5, N_SCENES = 5
  !> Scene names as the CSV rows and --scene spell them (use_large_chain renames the chain's).
  character(len=14), public, protected :: scene_names(N_SCENES) = [character(len=14) :: &
    'particle', 'ellipse', 'pendulum', 'pendulum_walls', 'fpu_walls']

  !> Horizons: particle and pendulum as in the examples; the ellipse is chaotic, so only as far as
  !> the coarsest step's impact sequence still follows the exact one (docs/DESIGN.md §8); the walled
  !> pendulum over 10 s (18 impacts); the FPU chain over 2 s (41 impacts; its reference is a
  !> quad-precision Taylor integration, seconds per run).
  real(rk), public, protected :: t_final(N_SCENES) = [3.0_rk, 3.0_rk, 5.0_rk, 10.0_rk, 2.0_rk]

  ! physical parameters (the paper's)
  real(rk), parameter, public :: grav = 9.8_rk, mass = 1.0_rk
  real(rk), parameter, public :: ell_a = 1.0_rk, ell_b = 0.5_rk
  real(rk), parameter, public :: pend_l = 2.0_rk, pend_r = 1.5_rk
  ! walled planar pendulum: length, wall angle, initial speed (theta(0) = 0)
  real(rk), parameter, public :: pw_l = 1.0_rk, pw_wall = 1.0_rk, pw_omega0 = 4.0_rk
  ! FPU-beta chain: particles, quartic coefficient, walls at +-fpu_w
  integer, public, protected :: fpu_n = 32
  !> The large chain of the report (issue 28): its size and horizon, named by LARGE_CHAIN_NAME.
  integer, parameter, public :: LARGE_CHAIN_N = 1024
  real(rk), parameter, public :: LARGE_CHAIN_T = 0.5_rk
  character(len=*), parameter, public :: LARGE_CHAIN_NAME = 'fpu_walls_1024'
  real(rk), parameter, public :: fpu_beta = 1.0_rk, fpu_w = 0.6_rk
  !> Taylor steps of the FPU reference: the first is used, the second checks it.
  real(rk), parameter, public :: fpu_ref_steps(2) = [0.01_rk, 0.005_rk]

  public :: initial_state, initial_momentum, reference_at, exact_energy0, impact_time_error, median, repeats_done
  !> Most timed repeats of one run (the drivers' timing arrays have this size).
  integer, parameter, public :: MAX_REPEATS = 2001
  public :: fpu_reference, use_large_chain, scene_argument
  public :: wall_now, cpu_now, energy_of_velocity, pend_f

contains

  !> The FPU scene becomes the large chain (LARGE_CHAIN_N particles over LARGE_CHAIN_T, the same
  !> walls, spring and initial shape): its rows are named LARGE_CHAIN_NAME. Called once, before any run.
  subroutine use_large_chain()
    fpu_n = LARGE_CHAIN_N
    t_final(SCENE_FPU) = LARGE_CHAIN_T
    scene_names(SCENE_FPU) = LARGE_CHAIN_NAME
  end subroutine use_large_chain

  !> A driver's scene argument: LARGE_CHAIN_NAME switches to the large chain (use_large_chain);
  !> every name is returned as given, for the drivers' scene filters.
  function scene_argument(arg) result(name)
    character(len=*), intent(in) :: arg
    character(len=:), allocatable :: name
    name = trim(arg)
    if (name == LARGE_CHAIN_NAME) call use_large_chain()
  end function scene_argument

  !> Initial configuration and velocity at t = 0 (pendulum: (theta, phi) with phidot = f thetadot).
  subroutine initial_state(scene, q0, qd0)
    integer, intent(in) :: scene
    real(rk), allocatable, intent(out) :: q0(:), qd0(:)
    integer :: i
    select case (scene)
    case (SCENE_PARTICLE)
      q0 = [0.0_rk, 1.0_rk]; qd0 = [1.0_rk, 0.0_rk]
    case (SCENE_ELLIPSE)
      q0 = [pi / 2.0_rk, 0.0_rk, 3.5_rk]; qd0 = [-3.0_rk, 2.0_rk, 0.0_rk]
    case (SCENE_PWALLS)
      q0 = [0.0_rk]; qd0 = [pw_omega0]
    case (SCENE_FPU)
      ! the reference's n = 32 check (test/core/test_ref_fpu_walls.pf)
      allocate (q0(fpu_n), qd0(fpu_n))
      do i = 1, fpu_n
        q0(i) = 0.4_rk * fpu_w * sin(2 * pi * i / (fpu_n + 1))
        qd0(i) = 1.2_rk * sin(3 * pi * i / (fpu_n + 1)) + 0.8_rk * sin(pi * i / (fpu_n + 1))
      end do
    case default
      q0 = [0.75_rk * pi, 0.0_rk]; qd0 = [pi / 4.0_rk, (pi + 0.5_rk) * pi / 4.0_rk]
    end select
  end subroutine initial_state

  !> The exact initial momentum p(0) = dL/dqdot = M(q0) qdot0 (what a user passes to
  !> init_from_momentum).
  subroutine initial_momentum(scene, p0)
    integer, intent(in) :: scene
    real(rk), allocatable, intent(out) :: p0(:)
    real(rk), allocatable :: q0(:), qd0(:)
    call initial_state(scene, q0, qd0)
    select case (scene)
    case (SCENE_ELLIPSE)
      p0 = [mass * (ell_a**2 + ell_b**2) / 4.0_rk * qd0(1), mass * qd0(2), mass * qd0(3)]
    case (SCENE_PENDULUM)
      p0 = mass * pend_l**2 * [qd0(1), sin(q0(1))**2 * qd0(2)]
    case (SCENE_PWALLS)
      p0 = mass * pw_l**2 * qd0
    case default
      p0 = mass * qd0
    end select
  end subroutine initial_momentum

  elemental real(rk) function pend_f(theta)
    real(rk), intent(in) :: theta
    pend_f = pi + cos(theta)**2
  end function pend_f

  !> Energy from configuration and velocity (same formula for every method).
  real(rk) function energy_of_velocity(scene, q, qd) result(e)
    integer, intent(in) :: scene
    real(rk), intent(in) :: q(:), qd(:)
    select case (scene)
    case (SCENE_PARTICLE)
      e = 0.5_rk * mass * sum(qd**2) + mass * grav * q(2)
    case (SCENE_ELLIPSE)
      e = 0.5_rk * (mass * (ell_a**2 + ell_b**2) / 4.0_rk * qd(1)**2 + mass * (qd(2)**2 + qd(3)**2)) &
          + mass * grav * q(3)
    case (SCENE_PWALLS)
      e = 0.5_rk * mass * pw_l**2 * qd(1)**2 - mass * grav * pw_l * cos(q(1))
    case (SCENE_FPU)
      e = 0.5_rk * sum(qd**2) + fpu_potential(q)
    case default
      e = 0.5_rk * mass * pend_l**2 * (qd(1)**2 + sin(q(1))**2 * qd(2)**2) + mass * grav * pend_l * cos(q(1))
    end select
  end function energy_of_velocity

  !> Potential of the FPU chain, sum over the n + 1 springs of r^2/2 + beta r^4/4.
  pure real(rk) function fpu_potential(x) result(v)
    real(rk), intent(in) :: x(:)
    real(rk) :: r(0:size(x))
    integer :: n
    n = size(x)
    r(0) = x(1); r(1:n - 1) = x(2:n) - x(1:n - 1); r(n) = -x(n)
    v = sum(0.5_rk * r**2 + 0.25_rk * fpu_beta * r**4)
  end function fpu_potential

  real(rk) function exact_energy0(scene) result(e)
    integer, intent(in) :: scene
    real(rk), allocatable :: q0(:), qd0(:)
    call initial_state(scene, q0, qd0)
    select case (scene)
    case (SCENE_ELLIPSE)
      e = ellipse_energy(ellipse_params(), q0, qd0)
    case (SCENE_PENDULUM)
      e = pendulum_energy(pendulum_params(), q0(1), qd0(1))
    case default
      e = energy_of_velocity(scene, q0, qd0)
    end select
  end function exact_energy0

  !> Reference configuration and velocity at time t, and the reference impact times in (0, t].
  !> The last answer of each scene is kept (the FPU reference costs seconds; every run of a sweep
  !> asks for the same final time).
  subroutine reference_at(scene, t, q, qd, times, status)
    integer, intent(in) :: scene
    real(rk), intent(in) :: t
    real(rk), allocatable, intent(out) :: q(:), qd(:), times(:)
    integer, intent(out) :: status
    real(rk), allocatable :: q0(:), qd0(:)
    real(rk) :: x, y, vx, vy, q3(3), v3(3), th, ph, thd
    integer :: n
    type :: cached_t
      logical :: have = .false.
      real(rk) :: t = 0.0_rk
      integer :: status = 0
      real(rk), allocatable :: q(:), qd(:), times(:)
    end type cached_t
    type(cached_t), save :: cache(N_SCENES)
    if (cache(scene)%have) then
      if (cache(scene)%t == t) then
        q = cache(scene)%q; qd = cache(scene)%qd; times = cache(scene)%times
        status = cache(scene)%status
        return
      end if
    end if
    call initial_state(scene, q0, qd0)
    status = 0
    select case (scene)
    case (SCENE_PWALLS)
      allocate (q(1), qd(1))
      call pendulum_walls_exact(pendulum_walls_params(g=grav, ell=pw_l, theta_w=pw_wall, m=mass), &
                                q0(1), qd0(1), t, q(1), qd(1), n, times, status)
    case (SCENE_FPU)
      call fpu_reference(t, fpu_ref_steps(1), q, qd, times, status)
    case (SCENE_PARTICLE)
      call particle_exact(q0(2), qd0(1), qd0(2), grav, t, x, y, vx, vy, times, n)
      q = [x, y]; qd = [vx, vy]
    case (SCENE_ELLIPSE)
      call ellipse_exact(ellipse_params(), q0, qd0, t, q3, v3, times, n, status=status)
      q = q3; qd = v3
    case default
      call pendulum_exact(pendulum_params(), q0(1), qd0(1), q0(2), t, th, ph, thd, times, n, status)
      q = [th, ph]; qd = [thd, pend_f(th) * thd]
    end select
    cache(scene)%have = .true.; cache(scene)%t = t; cache(scene)%status = status
    cache(scene)%q = q; cache(scene)%qd = qd; cache(scene)%times = times
  end subroutine reference_at

  !> The FPU chain's event-driven quad-precision reference at time t with Taylor step `step`.
  subroutine fpu_reference(t, step, q, qd, times, status)
    real(rk), intent(in) :: t, step
    real(rk), allocatable, intent(out) :: q(:), qd(:), times(:)
    integer, intent(out) :: status
    real(rk), allocatable :: q0(:), qd0(:)
    integer :: n
    call initial_state(SCENE_FPU, q0, qd0)
    allocate (q(fpu_n), qd(fpu_n))
    call fpu_walls_run(fpu_walls_params(beta=fpu_beta, w=fpu_w, step=step), q0, qd0, t, q, qd, n, &
                       times, stat=status)
  end subroutine fpu_reference

  !> Largest distance from a reference impact time to the nearest impact time of the method
  !> (huge when the method found no impact at all but the reference has some).
  real(rk) function impact_time_error(ref, got, n_got) result(err)
    real(rk), intent(in) :: ref(:), got(:)
    integer, intent(in) :: n_got
    integer :: i
    err = 0.0_rk
    do i = 1, size(ref)
      if (n_got == 0) then
        err = huge(1.0_rk); return
      end if
      err = max(err, minval(abs(got(1:n_got) - ref(i))))
    end do
  end function impact_time_error

  !> Whether timed repeats 1 .. r of one run are enough: once they sum to 1 s (at least 3 of them)
  !> or to 0.1 s (at least 9), or MAX_REPEATS were made. Runs of a few microseconds are thus
  !> repeated hundreds of times, so that their median is not that of a handful of runs on a cold cache.
  logical function repeats_done(walls, r)
    real(rk), intent(in) :: walls(:)
    integer, intent(in) :: r
    repeats_done = (r >= 3 .and. sum(walls(1:r)) > 1.0_rk) .or. (r >= 9 .and. sum(walls(1:r)) > 0.1_rk) &
                   .or. r >= min(size(walls), MAX_REPEATS)
  end function repeats_done

  real(rk) function median(x)
    real(rk), intent(in) :: x(:)
    real(rk) :: y(size(x)), t
    integer :: i, j, n
    n = size(x); y = x
    do i = 2, n          ! insertion sort: at most MAX_REPEATS, once per row
      t = y(i); j = i - 1
      do while (j >= 1)
        if (y(j) <= t) exit
        y(j + 1) = y(j); j = j - 1
      end do
      y(j + 1) = t
    end do
    if (mod(n, 2) == 1) then
      median = y((n + 1) / 2)
    else
      median = 0.5_rk * (y(n / 2) + y(n / 2 + 1))
    end if
  end function median

  real(rk) function wall_now()
    integer(int64) :: c, r
    call system_clock(c, r)
    wall_now = real(c, rk) / real(r, rk)
  end function wall_now

  !> CPU time of the process in seconds, to the nanosecond (gfortran's cpu_time counts microseconds,
  !> a tenth of a run of the particle); cpu_time where clock_gettime fails.
  real(rk) function cpu_now()
    type(timespec_t) :: ts
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, ts) == 0) then
      cpu_now = real(ts%tv_sec, rk) + 1.0e-9_rk * real(ts%tv_nsec, rk)
    else
      call cpu_time(cpu_now)
    end if
  end function cpu_now
end module vci_results_common
