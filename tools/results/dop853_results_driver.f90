!> The peer a user with a smooth, non-stiff scene and events picks: a compiled DOP853 (results_dop853)
!> with event location on its 7th-order continuous extension, on the results scenes (the ODEs of
!> results_scene_ode). After every accepted step the gaps are evaluated; a decreasing crossing
!> (g > 0 at the step's start, g <= 0 at its end) is located by a safeguarded Illinois iteration on
!> g(dense output(x)) over the step, the state is taken at the bracket's outer end (g > 0, so a
!> return to the same wall in the next step is seen), the elastic impact map applied, and the
!> integration restarted there with the step size proposed before the impact. Several walls
!> crossing in one step: the earliest is handled first, the others are found in the next step.
!> This is what SciPy's solve_ivp(method="DOP853", events=...) does, without the interpreter.
!>
!>   dop853_results_driver check              order 8 on a smooth problem (the pendulum without
!>                                             walls), order of the dense output, event times on the
!>                                             particle, the ellipse and the walled pendulum against
!>                                             their exact solutions; exit status 1 if any fails
!>   dop853_results_driver sweep FILE [SCENE] tolerance sweep rtol = atol = 1e-3 .. 1e-13 -> CSV
!>                                            (SCENE: that scene only, for run_results.sh --scene)
!>   dop853_results_driver long SCENE DIR RTOL  ellipse (1.1e5 s) or walled pendulum (6e4 s)
!>   dop853_results_driver once SCENE RTOL    one untimed run (for callgrind: --toggle-collect='*run_dop*')
!>
!> Timing and error measures as in the CVODE driver (vci_results_common); the energy and the
!> constraint residual are evaluated at every accepted step, inside the timed loop.
module dop853_results_problem
  use vci_results_common
  use results_scene_ode
  implicit none
  integer :: scene = SCENE_PARTICLE   !< the problem scene_f evaluates
contains
  subroutine scene_f(t, y, f)
    real(rk), intent(in) :: t, y(:)
    real(rk), intent(out) :: f(:)
    call scene_rhs(scene, y, f)
  end subroutine scene_f
end module dop853_results_problem

program dop853_results_driver
  use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
  use vci_results_common
  use results_scene_ode
  use results_dop853
  use dop853_results_problem
  use vci_ref_pendulum_walls, only: pendulum_walls_params, pendulum_walls_exact
  implicit none

  !> What one run returns.
  type :: run_result_t
    real(rk), allocatable :: y(:), times(:), sample_t(:), sample_e(:)
    real(rk) :: emax = 0.0_rk, cmax = 0.0_rk, t_end = 0.0_rk
    integer :: n_impacts = 0, n_samples = 0, status = 0, steps = 0
    character(len=160) :: message = ''
  end type run_result_t

  character(len=512) :: mode, path, arg, dir
  real(rk) :: rtol_long

  if (command_argument_count() < 1) then
    write (error_unit, '(a)') 'usage: dop853_results_driver check | sweep FILE [SCENE] | long SCENE DIR RTOL'
    stop 2
  end if
  call get_command_argument(1, mode)
  select case (trim(mode))
  case ('check')
    call check()
  case ('sweep')
    call get_command_argument(2, path)
    arg = ''
    if (command_argument_count() >= 3) call get_command_argument(3, arg)
    call sweep(trim(path), scene_argument(arg))
  case ('once')
    call get_command_argument(2, path)
    call get_command_argument(3, arg)
    read (arg, *) rtol_long
    call once(trim(path), rtol_long)
  case ('long')
    call get_command_argument(2, path)
    call get_command_argument(3, dir)
    call get_command_argument(4, arg)
    read (arg, *) rtol_long
    call long_run(trim(path), trim(dir), rtol_long)
  case default
    write (error_unit, '(a)') 'unknown mode '//trim(mode)
    stop 2
  end select

contains

  !> Integrate the current scene from its exact start to t_end at rtol = atol = tol. sample_dt > 0:
  !> keep the largest |E - E0| of each window of that length.
  subroutine run_dop(tol, t_end, max_step, e0, res, sample_dt)
    real(rk), intent(in) :: tol, t_end, max_step, e0
    type(run_result_t), intent(out) :: res
    real(rk), intent(in), optional :: sample_dt
    type(dop853_t) :: d
    real(rk), allocatable :: q0(:), qd0(:), y(:), g_old(:), g_new(:)
    integer, allocatable :: found(:)
    real(rk) :: err, wmax, wend, x_hit, x, t_hit, t_last_hit, x0, g0, x1, g1
    integer :: n, nr, j, j_hit, ns, n_stalled, j_restart
    logical :: ok

    n = state_size(scene); nr = n_roots(scene)
    call initial_state(scene, q0, qd0)
    allocate (y(n), g_old(nr), g_new(nr), found(nr), res%times(64))
    y(1:n / 2) = q0; y(n / 2 + 1:) = qd0
    ns = 1
    if (present(sample_dt)) ns = int(t_end / sample_dt) + 2
    allocate (res%sample_t(ns), res%sample_e(ns))
    if (max_step > 0.0_rk) d%h_max = max_step
    call dop_init(d, scene_f, 0.0_rk, y, tol, tol, 0.0_rk)
    call scene_gaps(scene, y, g_old)
    res%emax = abs(scene_energy(scene, y) - e0)
    res%cmax = abs(scene_constraint(scene, y))
    wmax = 0.0_rk; wend = huge(1.0_rk)
    if (present(sample_dt)) wend = sample_dt
    t_last_hit = -huge(1.0_rk); n_stalled = 0; j_restart = 0
    do while (d%t < t_end)
      call dop_step(d, t_end, ok)
      if (.not. ok) then
        res%status = -1
        write (res%message, '(a,es12.5)') 'step size underflow or non-finite state at t = ', d%t
        exit
      end if
      call scene_gaps(scene, d%y, g_new)
      ! the earliest decreasing crossing of the step, located on the continuous extension
      j_hit = 0; x_hit = 2.0_rk
      do j = 1, nr
        if (g_old(j) > 0.0_rk .and. g_new(j) <= 0.0_rk) then
          if (.not. d%dense_ready) call dop_dense(d)
          x0 = 0.0_rk; g0 = g_old(j); x1 = 1.0_rk; g1 = g_new(j)
          ! the wall just reflected from: its gap at the step's start is zero up to rounding, so
          ! the bracket is narrowed to samples of the step away from the start
          if (j == j_restart) call leave_wall(d, j, x0, g0, x1, g1)
          x = crossing(d, j, x0, g0, x1, g1)
          if (x < x_hit) then
            x_hit = x; j_hit = j
          end if
        end if
      end do
      if (j_hit > 0) then
        call dop_eval(d, x_hit, y)
        t_hit = d%t_old + x_hit * d%h_old
        ! impacts that no longer advance time (grazing contact, chatter): stop with a status, as
        ! vci's impacts-per-step limit does, instead of looping
        if (t_hit - t_last_hit <= 1.0e-12_rk * max(1.0_rk, abs(t_hit))) then
          n_stalled = n_stalled + 1
        else
          n_stalled = 0
        end if
        t_last_hit = t_hit
        if (n_stalled >= 16) then
          res%status = -2
          write (res%message, '(a,es14.7)') '16 impacts within 1e-12 relative of each other at t = ', t_hit
          exit
        end if
        res%n_impacts = res%n_impacts + 1
        if (res%n_impacts > size(res%times)) call grow(res%times)
        res%times(res%n_impacts) = t_hit
        found = 0; found(j_hit) = 1
        call scene_impact(scene, y, found)
        d%t = t_hit
        j_restart = j_hit
        call dop_restart(d, y)
        call scene_gaps(scene, d%y, g_new)
      end if
      if (j_hit == 0) j_restart = 0
      g_old = g_new
      res%steps = res%steps + 1
      err = abs(scene_energy(scene, d%y) - e0)
      res%emax = max(res%emax, err)
      res%cmax = max(res%cmax, abs(scene_constraint(scene, d%y)))
      if (present(sample_dt)) then
        do while (d%t > wend .and. res%n_samples < ns)
          res%n_samples = res%n_samples + 1
          res%sample_t(res%n_samples) = wend; res%sample_e(res%n_samples) = wmax
          wmax = 0.0_rk; wend = wend + sample_dt
        end do
        wmax = max(wmax, err)
      end if
    end do
    if (present(sample_dt) .and. res%n_samples < ns) then
      res%n_samples = res%n_samples + 1
      res%sample_t(res%n_samples) = d%t; res%sample_e(res%n_samples) = wmax
    end if
    res%y = d%y
    res%t_end = d%t
  end subroutine run_dop

  !> The point x in (0, 1] of the last step where gap j crosses zero downwards (g(0) = g0 > 0 >=
  !> g(1) = g1), by Illinois (regula falsi halving the weight of an end kept twice) with bisection
  !> when an iterate leaves the bracket; returns the bracket's outer end (g > 0) once the bracket
  !> is a few ulps of t wide.
  real(rk) function crossing(d, j, x0, g0, x1, g1) result(xl)
    type(dop853_t), intent(in) :: d
    integer, intent(in) :: j
    real(rk), intent(in) :: x0, g0, x1, g1
    real(rk) :: xr, gl, gr, x, gx, y(d%n), g(n_roots(scene)), width
    integer :: it, side
    xl = x0; xr = x1; gl = g0; gr = g1; side = 0
    width = 4.0_rk * epsilon(1.0_rk) * max(abs(d%t), abs(d%h_old)) / abs(d%h_old)
    do it = 1, 200
      if (xr - xl <= width) exit
      x = (xl * gr - xr * gl) / (gr - gl)
      if (.not. (x > xl .and. x < xr)) x = 0.5_rk * (xl + xr)
      call dop_eval(d, x, y)
      call scene_gaps(scene, y, g)
      gx = g(j)
      if (gx > 0.0_rk) then
        xl = x; gl = gx
        if (side == -1) gr = 0.5_rk * gr
        side = -1
      else
        xr = x; gr = gx
        if (side == 1) gl = 0.5_rk * gl
        side = 1
      end if
    end do
  end function crossing

  !> After a reflection from wall j at the step's start, a bracket [x0, x1] of the return to it
  !> that excludes the start (where g is zero up to rounding): the samples x = k/8 (k = 1..7) up
  !> to the first back in the wall (g <= 0); if x = 1/8 is already back, x = 2^-m / 8 towards the
  !> start until one is outside (g > 0). Unchanged (x0 = 0) if every sample is in the wall.
  subroutine leave_wall(d, j, x0, g0, x1, g1)
    type(dop853_t), intent(in) :: d
    integer, intent(in) :: j
    real(rk), intent(inout) :: x0, g0, x1, g1
    real(rk) :: x, gx
    integer :: k
    do k = 1, 7
      x = k / 8.0_rk
      gx = gap_at(d, j, x)
      if (.not. gx > 0.0_rk) then
        x1 = x; g1 = gx
        exit
      end if
      x0 = x; g0 = gx
    end do
    if (x0 > 0.0_rk) return
    do k = 1, 45
      x = x1 / 2.0_rk
      gx = gap_at(d, j, x)
      if (gx > 0.0_rk) then
        x0 = x; g0 = gx
        return
      end if
      x1 = x; g1 = gx
    end do
  end subroutine leave_wall

  real(rk) function gap_at(d, j, x)
    type(dop853_t), intent(in) :: d
    integer, intent(in) :: j
    real(rk), intent(in) :: x
    real(rk) :: y(d%n), g(n_roots(scene))
    call dop_eval(d, x, y)
    call scene_gaps(scene, y, g)
    gap_at = g(j)
  end function gap_at

  subroutine grow(a)
    real(rk), allocatable, intent(inout) :: a(:)
    real(rk), allocatable :: tmp(:)
    allocate (tmp(2 * size(a)))
    tmp(:size(a)) = a
    call move_alloc(tmp, a)
  end subroutine grow

  !> The ellipse's flight is a polynomial: an unbounded step could carry the body through a short
  !> dip of the gap unseen (the same bound as the CVODE and SciPy peers).
  real(rk) function max_step_of(sc)
    integer, intent(in) :: sc
    max_step_of = merge(0.05_rk, 0.0_rk, sc == SCENE_ELLIPSE)
  end function max_step_of

  subroutine sweep(file, only_scene)
    character(len=*), intent(in) :: file
    character(len=*), intent(in) :: only_scene   !< a scene name, or empty for every scene
    integer :: unit, k, r, reps, rstat, nq, isc
    type(run_result_t) :: res
    real(rk), allocatable :: qref(:), qdref(:), tref(:)
    real(rk) :: tol, walls(MAX_REPEATS), cpus(MAX_REPEATS), w0, c0, e0, err_final, err_impact
    open (newunit=unit, file=file, status='replace', action='write')
    write (unit, '(a)') 'scene,method,param,wall_median,cpu_median,reps,err_final,err_energy,err_impact,' // &
      'n_impacts,n_ref_impacts,steps,status,err_constraint'
    do isc = 1, N_SCENES
      if (len(only_scene) > 0 .and. only_scene /= trim(scene_names(isc))) cycle
      ! the module variable the callbacks read is set, not used as the DO variable: at -O3 a DO
      ! variable may live in a register while the loop runs, and the callbacks saw a stale scene
      scene = isc
      call reference_at(scene, t_final(scene), qref, qdref, tref, rstat)
      e0 = exact_energy0(scene)
      nq = state_size(scene) / 2
      do k = 3, 13
        tol = 10.0_rk**(-k)
        reps = 0
        do r = 1, size(walls)
          w0 = wall_now(); c0 = cpu_now()
          call run_dop(tol, t_final(scene), max_step_of(scene), e0, res)
          walls(r) = wall_now() - w0; cpus(r) = cpu_now() - c0
          reps = r
          if (res%status /= 0) exit
          if (repeats_done(walls, r)) exit
        end do
        if (res%status /= 0) then
          write (error_unit, '(a,es9.2,a)') trim(scene_names(scene))//' dop853 tol ', tol, ': '//trim(res%message)
          write (unit, '(a,",",a,",",es10.3,",",9(a,","),i0,",nan")') trim(scene_names(scene)), 'dop853', tol, &
            ('nan', r = 1, 9), res%status
          cycle
        end if
        err_final = maxval(abs(res%y(1:nq) - qref))
        err_impact = impact_time_error(tref, res%times, res%n_impacts)
        write (unit, '(a,",",a,",",es10.3,",",es12.5,",",es12.5,",",i0,",",3(es12.5,","),i0,",",i0,",",i0,",",i0,",",es12.5)') &
          trim(scene_names(scene)), 'dop853', tol, median(walls(1:reps)), median(cpus(1:reps)), reps, &
          err_final, res%emax, err_impact, res%n_impacts, size(tref), res%steps, res%status, res%cmax
        flush (unit)
      end do
      write (output_unit, '(a)') 'dop853 sweep: '//trim(scene_names(scene))//' done'
      flush (output_unit)
    end do
    close (unit)
  end subroutine sweep

  !> Long run (ellipse 1.1e5 s, walled pendulum 6e4 s; >= 10^5 impacts) at one tolerance: the
  !> largest |E - E0| of each 10 s window, and the cost.
  subroutine long_run(scene_name, dir, tol)
    character(len=*), intent(in) :: scene_name, dir
    real(rk), intent(in) :: tol
    type(run_result_t) :: res
    real(rk) :: w0, c0, wall, cpu, t_end
    integer :: unit, sunit, i
    character(len=24) :: tag
    select case (scene_name)
    case ('ellipse'); scene = SCENE_ELLIPSE; t_end = 1.1e5_rk
    case ('pendulum_walls'); scene = SCENE_PWALLS; t_end = 6.0e4_rk
    case default
      write (error_unit, '(a)') 'long: scene must be ellipse or pendulum_walls'
      stop 2
    end select
    write (tag, '(es8.1)') tol
    w0 = wall_now(); c0 = cpu_now()
    call run_dop(tol, t_end, max_step_of(scene), exact_energy0(scene), res, 10.0_rk)
    wall = wall_now() - w0; cpu = cpu_now() - c0
    if (res%status /= 0) write (error_unit, '(a)') 'dop853 long run: '//trim(res%message)
    open (newunit=sunit, file=dir//'/long_'//scene_name//'_dop853_'//trim(adjustl(tag))//'_summary.csv', &
          status='replace', action='write')
    write (sunit, '(a)') 'scene,method,param,wall,cpu,max_energy_error,final_energy_error,n_impacts,t_end,status'
    write (sunit, '(a,",",a,",",es10.3,",",es12.5,",",es12.5,",",es12.5,",",es12.5,",",i0,",",es14.7,",",i0)') &
      scene_name, 'dop853', tol, wall, cpu, res%emax, res%sample_e(res%n_samples), res%n_impacts, res%t_end, &
      res%status
    close (sunit)
    open (newunit=unit, file=dir//'/long_'//scene_name//'_dop853_'//trim(adjustl(tag))//'.csv', &
          status='replace', action='write')
    write (unit, '(a)') 't,energy_error'
    do i = 1, res%n_samples
      write (unit, '(es14.7,",",es12.5)') res%sample_t(i), res%sample_e(i)
    end do
    close (unit)
    write (output_unit, '(a,f7.1,a,i0,a)') 'dop853 long run: '//scene_name//' '//trim(adjustl(tag))//' done (', &
      cpu, ' s CPU, ', res%n_impacts, ' impacts)'
    flush (output_unit)
  end subroutine long_run

  !> One run of a scene at rtol = atol = tol, and its final error.
  subroutine once(scene_name, tol)
    character(len=*), intent(in) :: scene_name
    real(rk), intent(in) :: tol
    type(run_result_t) :: res
    real(rk), allocatable :: qref(:), qdref(:), tref(:)
    integer :: rstat
    scene = findloc(scene_names, scene_name, 1)
    if (scene == 0) then
      write (error_unit, '(a)') 'once: unknown scene '//scene_name
      stop 2
    end if
    call run_dop(tol, t_final(scene), max_step_of(scene), exact_energy0(scene), res)
    call reference_at(scene, t_final(scene), qref, qdref, tref, rstat)
    write (output_unit, '(a,es10.3,a,i0,a,i0,a,es10.3)') 'dop853 tol ', tol, ' status ', res%status, ' steps ', &
      res%steps, ' final error ', maxval(abs(res%y(1:state_size(scene) / 2) - qref))
  end subroutine once

  ! ---- the checks -------------------------------------------------------------------------------

  !> The pendulum without walls (walls beyond its amplitude of 1.39 rad) in closed form.
  subroutine pendulum_exact_at(t, y)
    real(rk), intent(in) :: t
    real(rk), intent(out) :: y(2)
    real(rk), allocatable :: times(:)
    integer :: n, st
    call pendulum_walls_exact(pendulum_walls_params(g=grav, ell=pw_l, theta_w=3.0_rk, m=mass), &
                              0.0_rk, pw_omega0, t, y(1), y(2), n, times, st)
    if (st /= 0 .or. n /= 0) error stop 'check: the wall-free pendulum reference failed'
  end subroutine pendulum_exact_at

  !> Least-squares slope of log e against log h.
  real(rk) function slope(h, e)
    real(rk), intent(in) :: h(:), e(:)
    real(rk) :: x(size(h)), y(size(h))
    x = log(h); y = log(e)
    slope = sum((x - sum(x) / size(x)) * (y - sum(y) / size(y))) / sum((x - sum(x) / size(x))**2)
  end function slope

  subroutine verdict(name, value, lo, hi, failures)
    character(len=*), intent(in) :: name
    real(rk), intent(in) :: value, lo, hi
    integer, intent(inout) :: failures
    logical :: pass
    pass = value >= lo .and. value <= hi
    if (.not. pass) failures = failures + 1
    write (output_unit, '(a,a,es11.4,a,es9.2,a,es9.2,a)') merge('PASS ', 'FAIL ', pass), name//': ', value, &
      '  (accepted ', lo, ' .. ', hi, ')'
  end subroutine verdict

  !> The checks. Order: fixed steps h = 2/N over t = 2 s on the wall-free pendulum, N = 24 .. 60,
  !> errors 2e-10 .. 1e-13, above round-off: the slope must be 8 +- 0.3. Dense output: one step
  !> from the exact state, the interpolant at the step's middle against the exact solution: a
  !> local error O(h^8) for the 7th-order extension, slope 8 +- 0.5. Events: the particle and the
  !> ellipse fly on polynomials of degree 2, which DOP853 and its extension reproduce exactly, so
  !> their impact times and final states must come out at round-off (<= 1e-12) at any tolerance;
  !> the walled pendulum's (non-polynomial flight) within 1e-9 at rtol 1e-12. The ellipse over 600 s
  !> (~600 impacts) must run through (no stall of impacts at one time) with |E - E0| <= 1e-8.
  subroutine check()
    integer, parameter :: ns(5) = [24, 30, 38, 48, 60]
    real(rk) :: h(5), e(5), ed(5), y(2), yx(2), t_end
    type(dop853_t) :: d
    type(run_result_t) :: res
    real(rk), allocatable :: qref(:), qdref(:), tref(:)
    integer :: i, k, failures, rstat, nq, isc
    failures = 0
    scene = SCENE_PWALLS
    t_end = 2.0_rk
    call pendulum_exact_at(t_end, yx)
    do i = 1, size(ns)
      h(i) = t_end / ns(i)
      call dop_init(d, scene_f, 0.0_rk, [0.0_rk, pw_omega0], 1.0_rk, 1.0_rk, h(i))
      do k = 1, ns(i)
        call dop_fixed_step(d, h(i))
      end do
      e(i) = maxval(abs(d%y - yx))
      ! one step from the exact start, continuous extension at the middle
      call dop_init(d, scene_f, 0.0_rk, [0.0_rk, pw_omega0], 1.0_rk, 1.0_rk, h(i))
      call dop_fixed_step(d, h(i))
      call dop_dense(d)
      call dop_eval(d, 0.5_rk, y)
      call pendulum_exact_at(0.5_rk * h(i), yx)
      ed(i) = maxval(abs(y - yx))
      call pendulum_exact_at(t_end, yx)
      write (output_unit, '(a,es10.3,a,es10.3,a,es10.3)') 'h ', h(i), '  error at t = 2: ', e(i), &
        '  dense output at the middle of one step h: ', ed(i)
    end do
    call verdict('order of DOP853 (fixed steps, wall-free pendulum)', slope(h, e), 7.7_rk, 8.3_rk, failures)
    call verdict('order of the local error of the dense output', slope(h, ed), 7.5_rk, 8.5_rk, failures)
    do isc = SCENE_PARTICLE, SCENE_ELLIPSE
      scene = isc   ! not the DO variable itself (see sweep)
      call reference_at(scene, t_final(scene), qref, qdref, tref, rstat)
      nq = state_size(scene) / 2
      call run_dop(1.0e-6_rk, t_final(scene), max_step_of(scene), exact_energy0(scene), res)
      call verdict(trim(scene_names(scene))//': impacts found minus reference', real(res%n_impacts - size(tref), rk), &
                   0.0_rk, 0.0_rk, failures)
      call verdict(trim(scene_names(scene))//': impact-time error at rtol 1e-6 (exact flight)', &
                   impact_time_error(tref, res%times, res%n_impacts), 0.0_rk, 1.0e-12_rk, failures)
      call verdict(trim(scene_names(scene))//': final error at rtol 1e-6 (exact flight)', &
                   maxval(abs(res%y(1:nq) - qref)), 0.0_rk, 1.0e-12_rk, failures)
    end do
    scene = SCENE_PWALLS
    call reference_at(scene, t_final(scene), qref, qdref, tref, rstat)
    call run_dop(1.0e-12_rk, t_final(scene), 0.0_rk, exact_energy0(scene), res)
    call verdict('pendulum_walls: impacts found minus reference', real(res%n_impacts - size(tref), rk), &
                 0.0_rk, 0.0_rk, failures)
    call verdict('pendulum_walls: impact-time error at rtol 1e-12', &
                 impact_time_error(tref, res%times, res%n_impacts), 0.0_rk, 1.0e-9_rk, failures)
    call verdict('pendulum_walls: final error at rtol 1e-12', maxval(abs(res%y(1:1) - qref)), 0.0_rk, 1.0e-9_rk, &
                 failures)
    ! a long chaotic run with fast returns to the floor right after a reflection (the first one
    ! near t = 486 s): every return located away from the restart point, energy kept
    scene = SCENE_ELLIPSE
    call run_dop(1.0e-10_rk, 600.0_rk, max_step_of(scene), exact_energy0(scene), res)
    call verdict('ellipse over 600 s at rtol 1e-10: status', real(res%status, rk), 0.0_rk, 0.0_rk, failures)
    call verdict('ellipse over 600 s at rtol 1e-10: largest |E - E0|', res%emax, 0.0_rk, 1.0e-8_rk, failures)
    if (failures > 0) then
      write (error_unit, '(i0,a)') failures, ' DOP853 check(s) failed'
      stop 1
    end if
    write (output_unit, '(a)') 'DOP853 checks passed'
  end subroutine check
end program dop853_results_driver
