!> Cost of the explicit compositions (issue 32, item 6): the library's regular step against a
!> hand-written loop of the same composition (the same kick–drift–kick arithmetic, so the same
!> bits: checked), and an impact step against a regular step. Scene: the pendulum (m = 1, g = 9.8,
!> l = 1) from θ = 0, θ' = 4; free for the regular steps, between walls at ±1 rad for the impacts.
!>
!>   vci_bench_composition [order]                    timed runs (best of 5), ratios
!>   vci_bench_composition --profile lib|step|hand|walls|far order   one run of the *run_timed* routine,
!>                                                for callgrind --toggle-collect='*run_timed*':
!>                                                lib: integrate (no observer), step: step() one by
!>                                                one (H each step), walls: walls at ±1 rad (3520
!>                                                impacts), far: walls at ±2 rad (never reached:
!>                                                the walled run's regular step)
!>   vci_bench_composition --profile lib|hand order chain|kepler   the same for the FPU-β chain
!>                                                (n = 32, 2000 steps) or Kepler (n = 2, 100000
!>                                                steps), no walls, h = 0.01
!>   vci_bench_composition --scenes order         timed runs of those two (best of 5), ratios
!>   vci_bench_composition --chainwalls order n T h    the FPU-β chain of n particles between walls
!>                                                    at ±0.6 (the results' fpu_walls start) over T:
!>                                                    impacts, gradients (composed stages) per
!>                                                    impact beyond the regular steps', CPU time
!>   vci_bench_composition --sweep                    the walled pendulum over 10 s (18 impacts) from
!>                                                    the exact start: final error against the exact
!>                                                    solution and CPU time per run, orders 4 … 10
!> tools/bench/run_composition.sh writes docs/bench/composition.md from all three.
program vci_bench_composition
  use, intrinsic :: iso_fortran_env, only: int64, output_unit
  use vci
  use vci_composition, only: composition_coefficients
  use vci_scene_pendulum_walls_sep, only: pendulum_walls_sep_t, pendulum_walls_sep_model
  use vci_ref_pendulum_quad, only: pendulum_quad_t, pendulum_quad_state
  use vci_bench_composition_scenes, only: chain_sep_t, kepler_sep_t, chain_sep_model, kepler_sep_model, &
    chain_gradient, kepler_gradient, chain_n, run_timed_integrate, run_timed_steps, chain_walls_sep_t, &
    chain_walls_sep_model
  implicit none
  integer, parameter :: nsteps = 200000
  real(dp), parameter :: h = 0.01_dp
  character(len=16) :: arg, what, scene
  integer :: order, stat, rep, nimp_steps
  real(dp) :: q_lib, p_lib, q_hand, p_hand, q_step, p_step, t_lib, t_hand, t_walls, t_far, t_step, t
  real(dp) :: pair_walls(5), pair_far(5), ratio(5)
  order = 6
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg)
    if (arg == '--sweep') then
      call sweep(); stop
    end if
    if (arg == '--chainwalls') then
      call chain_walls(); stop
    end if
    if (arg == '--scenes') then
      call get_command_argument(2, arg); read (arg, *) order
      call time_scenes(order); stop
    end if
    if (arg == '--profile') then
      call get_command_argument(2, what); call get_command_argument(3, arg); read (arg, *) order
      scene = 'pendulum'
      if (command_argument_count() >= 4) call get_command_argument(4, scene)
      if (scene /= 'pendulum') then
        block
          real(dp), allocatable :: qs(:), ps(:)
          if (what == 'lib') call lib_scene_run(scene, order, qs, ps, stat, t)
          if (what == 'hand') call run_timed_hand_scene(scene, order, qs, ps)
        end block
        stop
      end if
      select case (what)
      case ('lib'); call lib_run(order, q_lib, p_lib, stat, t)
      case ('step'); call step_run(order, q_lib, p_lib, stat, t)
      case ('hand'); call run_timed_hand(order, q_hand, p_hand)
      case ('walls'); call walls_run(order, nimp_steps, stat, t)
      case ('far'); call walls_run(order, nimp_steps, stat, t, 2.0_dp)
        if (nimp_steps /= 0) error stop 'walls at 2 rad were reached'
      end select
      stop
    end if
    read (arg, *) order
  end if
  t_lib = huge(1.0_dp); t_hand = huge(1.0_dp); t_walls = huge(1.0_dp); t_far = huge(1.0_dp); t_step = huge(1.0_dp)
  do rep = 1, 5
    call lib_run(order, q_lib, p_lib, stat, t); t_lib = min(t_lib, t)
    if (stat /= VCI_OK) error stop 'library run failed'
    call step_run(order, q_step, p_step, stat, t); t_step = min(t_step, t)
    if (stat /= VCI_OK) error stop 'library run (step by step) failed'
    t = clock(); call run_timed_hand(order, q_hand, p_hand); t_hand = min(t_hand, clock() - t)
    call walls_run(order, nimp_steps, stat, pair_far(rep), 2.0_dp)
    t_far = min(t_far, pair_far(rep))
    if (stat /= VCI_OK) error stop 'far-walled run failed'
    call walls_run(order, nimp_steps, stat, pair_walls(rep))
    t_walls = min(t_walls, pair_walls(rep))
    if (stat /= VCI_OK) error stop 'walled run failed'
  end do
  write (output_unit, '(a,i0,a,i0,a,es9.2)') 'order ', order, '  steps ', nsteps, '  h ', h
  write (output_unit, '(a,l1)') 'library (integrate, step by step) and hand loop end in the same bits: ', &
    q_lib == q_hand .and. p_lib == p_hand .and. q_step == q_hand .and. p_step == p_hand
  write (output_unit, '(a,f8.1,a,f8.1,a,f8.1,a,f6.2,a,f6.2)') 'regular step: integrate ', 1.0e9_dp * t_lib / nsteps, &
    ' ns, step() ', 1.0e9_dp * t_step / nsteps, ' ns, hand loop ', 1.0e9_dp * t_hand / nsteps, ' ns; ratios ', &
    t_lib / t_hand, ', ', t_step / t_hand
  ! walled runs: the regular step with walls that are never reached, then the extra time of the
  ! run with impacts over it, per impact step. The impact steps are 1.8 % of the run, so the
  ! extra time is a small difference of two times: the minima of separate repeats could come
  ! from different load and made it negative. Each repeat's walled and never-reached runs are
  ! taken back to back and give one ratio; the median of the 5 and their range are printed.
  write (output_unit, '(a,f6.2)') 'walled regular step / free regular step ', t_far / t_lib
  do rep = 1, 5
    ratio(rep) = (pair_walls(rep) - pair_far(rep) * real(nsteps - nimp_steps, dp) / nsteps) / nimp_steps &
                 / (pair_far(rep) / nsteps)
  end do
  call sort5(ratio)
  write (output_unit, '(a,i0,a,f6.2,a,f6.2,a,f6.2,a)') 'impact steps: ', nimp_steps, &
    '; impact step / walled regular step ', ratio(3), ' (median of 5 back-to-back pairs; range ', ratio(1), &
    ' .. ', ratio(5), ')'

contains

  !> The steps of a scene's run (the chain's steps cost ~30 pendulum steps).
  integer function scene_steps(scene)
    character(len=*), intent(in) :: scene
    scene_steps = merge(2000, 100000, scene == 'chain')
  end function scene_steps

  !> The scene's start: the chain's lowest mode (amplitude 0.5) at rest, Kepler's ellipse of
  !> eccentricity 0.44 from pericentre.
  subroutine scene_start(scene, q, p)
    character(len=*), intent(in) :: scene
    real(dp), allocatable, intent(out) :: q(:), p(:)
    integer :: i
    if (scene == 'chain') then
      allocate (q(chain_n), p(chain_n))
      do i = 1, chain_n
        q(i) = 0.5_dp * sin(acos(-1.0_dp) * i / (chain_n + 1))
      end do
      p = 0.0_dp
    else
      q = [1.0_dp, 0.0_dp]; p = [0.0_dp, 1.2_dp]
    end if
  end subroutine scene_start

  !> The library's run (integrate, no observer) on the chain or Kepler.
  subroutine lib_scene_run(scene, order, q_end, p_end, stat, elapsed)
    character(len=*), intent(in) :: scene
    integer, intent(in) :: order
    real(dp), allocatable, intent(out) :: q_end(:), p_end(:)
    integer, intent(out) :: stat
    real(dp), intent(out) :: elapsed   !< seconds in integrate alone
    type(chain_sep_t), target :: chain
    type(kepler_sep_t), target :: kepler
    type(vci_integrator_t) :: integ
    real(dp), allocatable :: q(:), p(:)
    call scene_start(scene, q, p)
    if (scene == 'chain') then
      chain = chain_sep_model(); call integ%create(chain, h, stat)
    else
      kepler = kepler_sep_model(); call integ%create(kepler, h, stat)
    end if
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_COMPOSITION, order, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q, p, stat)
    elapsed = 0.0_dp
    if (stat == VCI_OK) call run_timed_integrate(integ, int(scene_steps(scene), i8), stat, elapsed)
    q_end = integ%configuration(); p_end = integ%momentum()
  end subroutine lib_scene_run

  !> The same composition written out for the chain or Kepler (M = I; the scene's force routine).
  subroutine run_timed_hand_scene(scene, order, q, p)
    character(len=*), intent(in) :: scene
    integer, intent(in) :: order
    real(dp), allocatable, intent(out) :: q(:), p(:)
    real(dp), allocatable :: gam(:), kick(:), dv(:)
    integer :: s, i, k, j, stat, n
    call composition_coefficients(order, gam, stat)
    s = size(gam)
    allocate (kick(s + 1))
    kick(1) = 0.5_dp * gam(1); kick(s + 1) = 0.5_dp * gam(s)
    do i = 2, s
      kick(i) = 0.5_dp * (gam(i - 1) + gam(i))
    end do
    call scene_start(scene, q, p)
    n = size(q)
    allocate (dv(n))
    call scene_force(n, q, dv)
    do k = 1, scene_steps(scene)
      do i = 1, s
        do j = 1, n
          p(j) = p(j) - (kick(i) * h) * dv(j)
          q(j) = q(j) + (gam(i) * h) * (1.0_dp * p(j))
        end do
        call scene_force(n, q, dv)
      end do
      do j = 1, n
        p(j) = p(j) - (kick(s + 1) * h) * dv(j)
      end do
    end do
  end subroutine run_timed_hand_scene

  !> The hand loop's force: Kepler's (n = 2) or the chain's gradient.
  subroutine scene_force(n, x, g)
    integer, intent(in) :: n
    real(dp), intent(in) :: x(n)
    real(dp), intent(out) :: g(n)
    if (n == 2) then
      call kepler_gradient(x, g)
    else
      call chain_gradient(n, x, g)
    end if
  end subroutine scene_force

  !> Timed runs (best of 5) of the chain and Kepler: library against hand loop, same bits checked.
  subroutine time_scenes(order)
    integer, intent(in) :: order
    character(len=8), parameter :: scenes(2) = [character(len=8) :: 'chain', 'kepler']
    real(dp), allocatable :: ql(:), pl(:), qh(:), ph(:)
    real(dp) :: tl, th, t0
    integer :: k, rep, st
    do k = 1, 2
      tl = huge(1.0_dp); th = huge(1.0_dp)
      do rep = 1, 5
        call lib_scene_run(trim(scenes(k)), order, ql, pl, st, t0); tl = min(tl, t0)
        if (st /= VCI_OK) error stop 'library run failed'
        t0 = clock(); call run_timed_hand_scene(trim(scenes(k)), order, qh, ph); th = min(th, clock() - t0)
      end do
      write (output_unit, '(a,a8,a,i0,a,l1,a,f9.1,a,f9.1,a,f6.2)') 'scene ', scenes(k), ' order ', order, &
        ' same bits ', all(ql == qh) .and. all(pl == ph), '; step: integrate ', &
        1.0e9_dp * tl / scene_steps(trim(scenes(k))), ' ns, hand ', 1.0e9_dp * th / scene_steps(trim(scenes(k))), &
        ' ns; ratio ', tl / th
    end do
  end subroutine time_scenes

  !> Insertion sort of 5 numbers (the median of the paired ratios).
  subroutine sort5(x)
    real(dp), intent(inout) :: x(5)
    real(dp) :: v
    integer :: i, j
    do i = 2, 5
      v = x(i); j = i - 1
      do while (j >= 1)
        if (x(j) <= v) exit
        x(j + 1) = x(j); j = j - 1
      end do
      x(j + 1) = v
    end do
  end subroutine sort5

  real(dp) function clock()
    integer(int64) :: c, r
    call system_clock(c, r)
    clock = real(c, dp) / real(r, dp)
  end function clock

  subroutine lib_run(order, q_end, p_end, stat, elapsed)
    integer, intent(in) :: order
    real(dp), intent(out) :: q_end, p_end
    integer, intent(out) :: stat
    real(dp), intent(out) :: elapsed   !< seconds in integrate (or the step loop) alone
    type(pendulum_walls_sep_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp) :: q(1), p(1)
    model = pendulum_walls_sep_model(.false.)
    call integ%create(model, h, stat)
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_COMPOSITION, order, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat)
    elapsed = 0.0_dp
    if (stat == VCI_OK) call run_timed_integrate(integ, int(nsteps, i8), stat, elapsed)
    q = integ%configuration(); p = integ%momentum()
    q_end = q(1); p_end = p(1)
  end subroutine lib_run

  !> The library run as a caller stepping one by one (step(): the general path, H each step).
  subroutine step_run(order, q_end, p_end, stat, elapsed)
    integer, intent(in) :: order
    real(dp), intent(out) :: q_end, p_end
    integer, intent(out) :: stat
    real(dp), intent(out) :: elapsed   !< seconds in integrate (or the step loop) alone
    type(pendulum_walls_sep_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp) :: q(1), p(1)
    model = pendulum_walls_sep_model(.false.)
    call integ%create(model, h, stat)
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_COMPOSITION, order, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat)
    elapsed = 0.0_dp
    if (stat == VCI_OK) call run_timed_steps(integ, nsteps, stat, elapsed)
    q = integ%configuration(); p = integ%momentum()
    q_end = q(1); p_end = p(1)
  end subroutine step_run

  !> The same composition written out: merged half kicks, M⁻¹ = 1/(m l²) = 1, force −m g l sin θ.
  subroutine run_timed_hand(order, q, p)
    integer, intent(in) :: order
    real(dp), intent(out) :: q, p
    real(dp), allocatable :: gam(:), kick(:)
    real(dp) :: f, v
    integer :: s, i, k, stat
    real(dp), parameter :: mass = 1.0_dp, grav = 9.8_dp, length = 1.0_dp, minv = 1.0_dp / (mass * length**2)
    call composition_coefficients(order, gam, stat)
    s = size(gam)
    allocate (kick(s + 1))
    kick(1) = 0.5_dp * gam(1); kick(s + 1) = 0.5_dp * gam(s)
    do i = 2, s
      kick(i) = 0.5_dp * (gam(i - 1) + gam(i))
    end do
    q = 0.0_dp; p = 4.0_dp
    f = -(mass * grav * length * sin(q))
    do k = 1, nsteps
      do i = 1, s
        p = p + (kick(i) * h) * f
        v = minv * p
        q = q + (gam(i) * h) * v
        f = -(mass * grav * length * sin(q))
      end do
      p = p + (kick(s + 1) * h) * f
    end do
  end subroutine run_timed_hand

  !> The chain between walls (--chainwalls order n T h): the results' fpu_walls start
  !> (q_i = 0.24 sin(2πi/(n+1)), q̇_i = 1.2 sin(3πi/(n+1)) + 0.8 sin(πi/(n+1))), one run of
  !> integrate over T (CPU time of that call), and the same run with the walls moved to ±10
  !> (never reached): the gradients and time beyond it, per impact. Also H(T) − H(0).
  subroutine chain_walls()
    type(chain_walls_sep_t), target :: model
    type(vci_integrator_t) :: integ
    type(vci_stats_t) :: st
    character(len=32) :: a
    integer :: order, n, stat, i, pass
    integer(i8) :: nst, grads(2)
    real(dp) :: tend, hh, t0, t1, cpu(2), e0, e1, pi
    real(dp), allocatable :: q(:), p(:), qe(:), pe(:)
    call get_command_argument(2, a); read (a, *) order
    call get_command_argument(3, a); read (a, *) n
    call get_command_argument(4, a); read (a, *) tend
    call get_command_argument(5, a); read (a, *) hh
    pi = acos(-1.0_dp)
    allocate (q(n), p(n))
    do i = 1, n
      q(i) = 0.24_dp * sin(2 * pi * i / (n + 1))
      p(i) = 1.2_dp * sin(3 * pi * i / (n + 1)) + 0.8_dp * sin(pi * i / (n + 1))
    end do
    nst = nint(tend / hh, i8)
    do pass = 1, 2
      model = chain_walls_sep_model(n)
      if (pass == 2) model%n_gaps = 0            ! the same run without walls: the regular steps' cost
      call integ%create(model, hh, stat)
      if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_COMPOSITION, order, stat)
      if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q, p, stat)
      if (stat /= VCI_OK) error stop 'chain set-up failed'
      call model%potential(q, e0, stat); e0 = e0 + 0.5_dp * sum(p**2)
      model%gradient_calls = 0
      call cpu_time(t0)
      call integ%integrate(nst, 1, stat)
      call cpu_time(t1)
      if (stat /= VCI_OK) then
        write (output_unit, '(a)') trim(integ%message()); error stop 'chain run failed'
      end if
      grads(pass) = model%gradient_calls; cpu(pass) = t1 - t0
      if (pass == 1) then
        st = integ%statistics()
        qe = integ%configuration(); pe = integ%momentum()
        call model%potential(qe, e1, stat); e1 = e1 + 0.5_dp * sum(pe**2)
      end if
    end do
    write (output_unit, '(a,i0,a,i0,a,es9.2,a,es9.2,a,i0,a,i0)') 'chain walls: order ', order, ' n ', n, ' T ', tend, &
      ' h ', hh, ' steps ', nst, ' impacts ', st%impacts
    write (output_unit, '(a,i0,a,i0,a,f10.1,a)') 'gradients: walled ', grads(1), ', free ', grads(2), &
      '; per impact beyond the free run ', real(grads(1) - grads(2), dp) / max(st%impacts, 1_i8), ' gradients'
    write (output_unit, '(a,f8.3,a,f8.3,a,f9.5,a,es10.2)') 'CPU: walled ', cpu(1), ' s, free ', cpu(2), &
      ' s; per impact ', (cpu(1) - cpu(2)) / max(st%impacts, 1_i8), ' s;  H(T) - H(0) ', e1 - e0
    write (output_unit, '(a,2es25.16)') 'end state: sum q, sum p ', sum(qe), sum(pe)
  end subroutine chain_walls

  !> Error against CPU time on the walled pendulum (T = 10 s): for each order and h, the final
  !> error max(|θ − θ_exact|, |θ' − θ'_exact|) and the best of 7 timings of the whole run
  !> (create, set_scheme, init, integrate); then the cheapest run reaching each error level.
  subroutine sweep()
    integer, parameter :: orders(4) = [4, 6, 8, 10], nh = 12
    real(dp), parameter :: levels(7) = [1.0e-4_dp, 1.0e-5_dp, 1.0e-6_dp, 1.0e-7_dp, 1.0e-8_dp, 1.0e-9_dp, 1.0e-10_dp]
    type(pendulum_walls_sep_t), target :: model
    type(vci_integrator_t) :: integ
    type(pendulum_quad_t) :: ref
    real(dp) :: hh, th, om, err(4, nh), cpu(4, nh), hs(4, nh), t0, t1, best, q(1), p(1)
    integer :: j, i, r, nst, stat, bi, bj, l
    ref%k = 9.8_dp; ref%theta_wall = 1.0_dp; ref%theta0 = 0.0_dp; ref%omega0 = 4.0_dp
    call pendulum_quad_state(ref, 10.0_dp, th, om)
    write (output_unit, '(a)') 'order  h          final error  CPU [ms]'
    do j = 1, 4
      do i = 1, nh
        hh = 0.5_dp * 0.75_dp**(i - 1)
        nst = nint(10.0_dp / hh); hh = 10.0_dp / nst
        best = huge(1.0_dp)
        do r = 1, 7
          call cpu_time(t0)
          model = pendulum_walls_sep_model(.true.)
          call integ%create(model, hh, stat)
          if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_COMPOSITION, orders(j), stat)
          if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat)
          if (stat == VCI_OK) call integ%integrate(int(nst, i8), 1, stat)
          call cpu_time(t1)
          best = min(best, t1 - t0)
        end do
        q = integ%configuration(); p = integ%momentum()
        err(j, i) = huge(1.0_dp)
        if (stat == VCI_OK) err(j, i) = max(abs(q(1) - th), abs(p(1) - om))
        cpu(j, i) = 1.0e3_dp * best; hs(j, i) = hh
        write (output_unit, '(i5,es11.3,es13.3,f10.3)') orders(j), hh, err(j, i), cpu(j, i)
      end do
    end do
    write (output_unit, '(a)') 'error <=   cheapest run (order, h, CPU [ms])'
    do l = 1, size(levels)
      best = huge(1.0_dp); bi = 0; bj = 0
      do j = 1, 4
        do i = 1, nh
          if (err(j, i) <= levels(l) .and. cpu(j, i) < best) then
            best = cpu(j, i); bi = i; bj = j
          end if
        end do
      end do
      if (bj > 0) write (output_unit, '(es9.1,i6,es11.3,f10.3)') levels(l), orders(bj), hs(bj, bi), best
    end do
  end subroutine sweep

  subroutine walls_run(order, impact_steps, stat, elapsed, theta_wall)
    integer, intent(in) :: order
    integer, intent(out) :: impact_steps, stat
    real(dp), intent(out) :: elapsed
    real(dp), intent(in), optional :: theta_wall   !< default 1 rad
    type(pendulum_walls_sep_t), target :: model
    type(vci_integrator_t) :: integ
    type(vci_stats_t) :: st
    model = pendulum_walls_sep_model(.true.)
    if (present(theta_wall)) model%theta_wall = theta_wall
    call integ%create(model, h, stat)
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_COMPOSITION, order, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat)
    elapsed = 0.0_dp
    if (stat == VCI_OK) call run_timed_integrate(integ, int(nsteps, i8), stat, elapsed)
    st = integ%statistics()
    impact_steps = int(st%impacts)   ! (h = 0.01: one impact per impact step)
  end subroutine walls_run
end program vci_bench_composition
