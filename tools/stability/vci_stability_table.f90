!> Regenerates the table of docs/STABILITY.md: runs every stability case through the library
!> (the same case runners as the test suites in test/stability) and prints one Markdown row per
!> case: what happens, the numbers, the status returned. See tools/stability/regenerate.sh.
program vci_stability_table
  use vci
  use vci_stab_run
  use vci_stab_cases
  implicit none
  type(run_summary_t) :: s
  real(dp) :: st(4), st0(4), a, b, c, dev, t_star, mags(5), alphas(9), ratios(5), hs(12), beta(0:1)
  real(dp) :: lags(40), rms(40), srms(0:1), maxdh(0:1)
  real(dp), allocatable :: e(:)
  integer :: i, j, k, mode, ne, nl, nfail
  integer(i8) :: nonfinite
  character(len=32) :: mname(0:1) = [character(len=32) :: 'discrete', 'hamiltonian']
  character(len=600) :: nums

  print '(a)', '| case | what happens | numbers | status |'
  print '(a)', '|---|---|---|---|'
  ! stiff
  do mode = 0, 1
    do i = -1, 3
      call stiff_case(10.0_dp**i, mode, 4000_i8, s)
      write (nums, '(a,i0,a,i0,a,i0,a,es8.1,a,f4.2,a,i0)') 'steps ', s%steps, ', impacts ', s%impacts, &
        ', max Newton it/step ', s%max_iterations_step, ', max |dH|/H ', s%max_dh / s%h0, &
        ', mean it/solve ', real(s%iterations, dp) / max(1_i8, s%solves), ', max |y| ', nint(s%max_abs_q)
      call row('stiff spring, h*omega = '//g0(10.0_dp**i)//', '//trim(mname(mode)), what_stiff(s), nums, s)
    end do
  end do
  ! magnitudes
  mags = [1.0e-8_dp, 1.0e-4_dp, 1.0_dp, 1.0e4_dp, 1.0e8_dp]
  do mode = 0, 1
    call magnitude_case(1.0_dp, 1.0_dp, 1.0e-2_dp, 600_i8, mode, s, st0)
    dev = 0.0_dp; nfail = 0
    do i = 1, 5
      do j = 1, 5
        call magnitude_case(mags(i), mags(j), 1.0e-2_dp, 600_i8, mode, s, st)
        if (s%status /= VCI_OK) then
          nfail = nfail + 1
          write (nums, '(a,es7.0,a,es7.0)') 'fails at m = ', mags(i), ', g = ', mags(j)
          cycle
        end if
        dev = max(dev, maxval(abs(st - st0)), abs(s%impact_t(1) - sqrt(2.0_dp)))
      end do
    end do
    write (nums, '(a,i0,a,es8.1,a)') '25 runs (m, g in 1e-8..1e8, h = 1e-2/sqrt(g)); ', nfail, &
      ' failed; max deviation of scaled state / impact times from m = g = 1: ', dev, &
      trim(merge(' (failure: m = g = 1e8, E ~ 1e16)', '                                 ', nfail > 0))
    call row('masses and g 1e-8 ... 1e8, '//trim(mname(mode)), &
      'impact times independent of m, scale as 1/sqrt(g); first impact sqrt(2)/sqrt(g) exactly', nums, s, nfail == 0)
  end do
  call magnitude_case(1.0_dp, 1.0e8_dp, 100.0_dp, 10_i8, 1, s, st)
  call row('g = 1e8 with h = 1e-2 (unscaled)', trim(merge('~35 bounces per step; every step split (safety net)', &
           '~35 bounces per step; stops at step 0              ', s%status == VCI_OK)), 'bounce period 2.8e-4 s', s)
  ! grazing
  do mode = 0, 1
    dev = 0.0_dp; c = 0.0_dp
    do k = 3, 12
      call graze_line_case(10.0_dp**(-k), mode, s, t_star, a, b)
      dev = max(dev, abs(a / 10.0_dp**(-k) - 1.0_dp)); c = max(c, abs(s%impact_t(1) - t_star))
    end do
    write (nums, '(a,es8.1,a,es8.1)') 'max rel. error of reflected normal speed ', dev, ', of impact time ', c
    call row('grazing line, v_n = 1e-3 ... 1e-12, '//trim(mname(mode)), &
      'one impact each, detected and reflected exactly (Newton starts at the exact linearised reflection)', nums, s)
  end do
  a = 9.8_dp * 1.0e-4_dp / 8.0_dp
  call graze_ceiling_case(0.5_dp * a, 0.205_dp, s)
  write (nums, '(a,es9.2,a,i0,a,es9.2)') 'apex above ceiling by ', 0.5_dp * a, ', impacts ', s%impacts, &
    ', smallest gap on grid ', s%min_gap
  call row('tangential touch between grid points (depth < g h^2/8)', &
    'detected by the poke screen (on by default): one impact', nums, s)
  call graze_ceiling_case(0.5_dp * a, 0.205_dp, s, poke=.false.)
  write (nums, '(a,es9.2,a,i0,a,es9.2)') 'apex above ceiling by ', 0.5_dp * a, ', impacts ', s%impacts, &
    ', smallest gap on grid ', s%min_gap
  call row('the same with set_poke_samples(.false.)', &
    'NOT detected: gaps are checked at grid points only; passes through by up to g h^2/8', nums, s)
  call graze_ceiling_case(1.01_dp * a, 0.205_dp, s)
  write (nums, '(a,es9.2,a,i0)') 'depth ', 1.01_dp * a, ', impacts ', s%impacts
  call row('touch deeper than g h^2/8', 'a grid point is outside: detected, one impact', nums, s)
  call graze_ceiling_case(0.0_dp, 0.2_dp, s)
  write (nums, '(a,i0,a,es9.2)') 'impacts ', s%impacts, ', smallest gap ', s%min_gap
  call row('apex exactly on the wall at a grid point', 'g = 0 to round-off: admissible, no impact', nums, s)
  ! alpha
  alphas = [0.5_dp, 1.0e-6_dp, 1.0e-12_dp, 1.0e-15_dp, 0.0_dp, 1.0_dp - 1.0e-6_dp, 1.0_dp - 1.0e-9_dp, &
            1.0_dp - 1.0e-11_dp, 1.0_dp - 1.0e-14_dp]
  do i = 1, size(alphas)
    call alpha_case(alphas(i), 0, s, t_star, a)
    call alpha_case(alphas(i), 1, s, t_star, b)
    write (nums, '(a,es9.2,a,f10.7,a,es9.2,a,es9.2)') 'impact time error ', s%impact_t(1) - t_star, &
      ', alpha recorded ', s%impact_alpha(1), ', y error at t=3: discrete ', a, ', hamiltonian ', b
    if (alphas(i) > 0.5_dp) then
      call row('impact at alpha = 1 - '//g0(1.0_dp - alphas(i)), what_alpha(alphas(i)), nums, s)
    else
      call row('impact at alpha = '//g0(alphas(i)), what_alpha(alphas(i)), nums, s)
    end if
  end do
  ! corner and close walls
  call corner_case(0.5625_dp, 0, s, a)
  write (nums, '(a,i0,a,es8.1)') 'impacts in that step ', s%max_impacts_step, ', error of final state ', a
  call row('corner reached in mid-step', 'both walls in one step, velocity reversed exactly', nums, s)
  call corner_case(0.5_dp, 0, s, a)
  write (nums, '(a,i0,a,es8.1)') 'impacts in that step ', s%max_impacts_step, ', error of final state ', a
  call row('corner reached exactly at a grid point', 'lands on both walls; next step reflects twice at alpha = 0', nums, s)
  do i = 1, 4
    ratios(1:4) = [1.0e-2_dp, 3.0e-3_dp, 1.0e-3_dp, 5.0e-4_dp]
    b = ratios(i)
    call close_walls_case(b, 1.0_dp, 0, 16, s, a)
    write (nums, '(a,i0,a,i0,a,es8.1)') 'impacts ', s%impacts, ', most in one step ', s%max_impacts_step, &
      ', error of y / d ', a
    call row('two walls d = '//g0(b)//' apart, travel 1e-2 per step', &
      trim(merge('all impacts of each step resolved, motion exact     ', &
                 'more than 16 impacts per step: stops with its status', s%status == VCI_OK)), nums, s)
  end do
  ! contact
  do mode = 0, 1
    call rest_case(0.0_dp, mode, 1000_i8, s)
    write (nums, '(a,i0,a,f6.3,a)') 'steps taken ', s%steps, ', returned after ', s%seconds, ' s'
    call row('at rest on the floor, '//trim(mname(mode)), &
      'zero normal speed: reflection = pass-through (double root); stops at step 0, never spins', nums, s)
  end do
  ratios = [10.0_dp, 1.0_dp, 0.3_dp, 0.05_dp, 0.01_dp]
  do mode = 0, 1
    do i = 1, 5
      call short_bounce_case(ratios(i), mode, 200_i8, s)
      write (nums, '(a,i0,a,i0,a,es8.1)') 'steps ', s%steps, ', impacts ', s%impacts, ', max |dH|/H ', s%max_dh / s%h0
      call row('bounce period = '//g0(ratios(i))//' h, '//trim(mname(mode)), what_bounce(ratios(i), s, mode), nums, s)
    end do
  end do
  ! degeneracy
  call pendulum_case(1.0e-3_dp, 5000_i8, .false., 0, s, a)
  write (nums, '(a,i0,a,es8.1,a,i0,a,f4.2)') 'impacts ', s%impacts, ', min |sin theta| on grid ', a, &
    ', fallbacks ', s%fallbacks, ', it/solve ', real(s%iterations, dp) / s%solves
  call row('pendulum through theta = pi (5 s, h = 1e-3)', &
           'n x n block singular at pi, augmented matrix regular: runs through', nums, s)
  call pendulum_case(1.0e-3_dp, 5000_i8, .true., 1, s, a)
  write (nums, '(a,i0,a,es8.1,a,i0)') 'impacts ', s%impacts, ', min |sin theta| ', a, ', fallbacks ', s%fallbacks
  call row('pendulum started at theta = pi, hamiltonian', 'runs through', nums, s)
  call massless_case(.true., s, a, b)
  write (nums, '(a,i0,a,es8.1,a,i0)') 'impacts ', s%impacts, ', max |z - x| ', a, ', fallbacks ', s%fallbacks
  call row('massless coordinate tied by a constraint', 'singular n x n block, regular augmented matrix: runs', nums, s)
  call massless_case(.false., s, a, b)
  write (nums, '(a,i0,a,i0,a,es8.1)') 'steps ', s%steps, ', least-squares fallbacks ', s%fallbacks, ', max |z| ', b
  call row('massless coordinate, unconstrained (singular)', &
    'steps and impacts by min-norm least squares (the massless coordinate stays put): runs', nums, s)
  ! step size
  hs = [1.0e-7_dp, 1.0e-6_dp, 1.0e-5_dp, 1.0e-4_dp, 1.0e-3_dp, 1.0e-2_dp, 0.1_dp, 0.3_dp, 0.5_dp, 1.0_dp, 3.0_dp, 10.0_dp]
  do i = 1, size(hs)
    do mode = 0, 1
      call step_size_case(hs(i), merge(0.5_dp, 1.2_dp, hs(i) < 1.0e-6_dp), mode, s, a, b)
      write (nums, '(a,es9.2,a,es8.1,a,i0)') 't1 error ', a, ', max |dH|/H ', b, ', impacts ', s%impacts
      call row('step h = '//g0(hs(i))//', '//trim(mname(mode)), what_h(hs(i), s, b), nums, s)
    end do
  end do
  ! long run
  allocate (e(400000))
  do mode = 0, 1
    call ellipse_long_case(10000000_i8, mode, s, e, ne, nonfinite)
    call growth_exponent(e, ne, 64, beta(mode), lags, rms, nl)
    srms(mode) = sqrt(sum((e(2:ne) - e(1:ne - 1))**2) / real(ne - 1, dp))
    maxdh(mode) = s%max_dh
    write (nums, '(a,i0,a,i0,a,es8.1,a,es8.1,a,f5.3,a,i0,a,f5.1,a)') 'impacts ', s%impacts, ', NaN steps ', nonfinite, &
      ', max |H - H0| ', s%max_dh, ' (H0 = 37.7), per-impact RMS ', srms(mode), ', growth exponent ', beta(mode), &
      ', most impacts/step ', s%max_impacts_step, ', ', s%seconds, ' s'
    call row('ellipse, 1e7 steps of 1e-2, '//trim(mname(mode)), &
      'no NaN; |H - H0| after impacts is a random walk (exponent ~1/2)', nums, s)
  end do

contains

  subroutine row(name, what, numbers, s, ok)
    character(len=*), intent(in) :: name, what, numbers
    type(run_summary_t), intent(in) :: s
    logical, intent(in), optional :: ok
    character(len=:), allocatable :: stat
    if (present(ok)) then
      stat = merge('0 ok (all)       ', 'see numbers      ', ok)
    else if (s%status == VCI_OK) then
      stat = '0 ok'
    else
      stat = g0i(s%status)//' '//vci_status_name(s%status)//': '//trim(s%message)
    end if
    print '(a)', '| '//esc(trim(name))//' | '//esc(trim(what))//' | '//esc(trim(numbers))//' | '//esc(trim(stat))//' |'
  end subroutine row

  !> Markdown table cells: a bar inside a cell is written \|.
  function esc(str) result(out)
    character(len=*), intent(in) :: str
    character(len=:), allocatable :: out
    integer :: i
    out = ''
    do i = 1, len(str)
      if (str(i:i) == '|') then
        out = out//'\|'
      else
        out = out//str(i:i)
      end if
    end do
  end function esc

  function what_stiff(s) result(w)
    type(run_summary_t), intent(in) :: s
    character(len=:), allocatable :: w
    if (s%status == VCI_OK) then
      w = 'runs through; no blow-up; energy bounded'
    else
      w = 'no blow-up; stops with the status shown (strongly curved stiff sub-step)'
    end if
  end function what_stiff

  function what_alpha(al) result(w)
    real(dp), intent(in) :: al
    character(len=:), allocatable :: w
    if (al == 0.0_dp) then
      w = 'lands exactly on the wall at a grid point (no impact there); next step reflects at alpha = 0'
    else if (al < 1.0e-9_dp) then
      w = 'start of the step is within 10 rtol of the wall: treated as on the wall, impact at alpha = 0'
    else if (1.0_dp - al <= 1.0e-10_dp) then
      w = '1 - alpha <= 1e-10: landed at the end of the step; impact at alpha = 0 of the next'
    else
      w = 'stage 1 finds alpha exactly (free fall exact)'
    end if
  end function what_alpha

  function what_bounce(r, s, mode) result(w)
    real(dp), intent(in) :: r
    type(run_summary_t), intent(in) :: s
    integer, intent(in) :: mode
    character(len=:), allocatable :: w
    if (r >= 1.0_dp) then
      w = 'one impact per bounce, all resolved'
    else if (s%status /= VCI_OK) then
      w = 'a 2nd bounce inside the step: stops with the status shown'
    else if (mode == 0) then
      w = 'runs on, but the paper''s condition adds ~m g^2 h^2/8 per impact: bounces wrong (not a failure status)'
    else
      w = 'several bounces per step, all resolved, H kept'
    end if
  end function what_bounce

  function what_h(h, s, dh) result(w)
    real(dp), intent(in) :: h, dh
    type(run_summary_t), intent(in) :: s
    character(len=:), allocatable :: w
    if (s%status /= VCI_OK) then
      w = 'several bounces per step: stops'
    else if (h < 1.0e-5_dp) then
      w = 'resolved; impact-time error from round-off ~ eps t^2/h^2 (velocity re-derived from position differences)'
    else if (dh > 1.0e-2_dp) then
      w = 'first bounce at the right time, but H wrong by the O(h^2) impact-condition change'
    else if (s%impacts > 1) then
      w = 'several bounces in the first step, all resolved'
    else
      w = 'first bounce resolved'
    end if
  end function what_h

  function g0(x) result(str)
    real(dp), intent(in) :: x
    character(len=:), allocatable :: str
    character(len=24) :: buf
    if (x == 0.0_dp) then
      str = '0'; return
    end if
    write (buf, '(es9.2)') x
    str = trim(adjustl(buf))
  end function g0

  function g0i(i) result(str)
    integer, intent(in) :: i
    character(len=:), allocatable :: str
    character(len=12) :: buf
    write (buf, '(i0)') i
    str = trim(buf)
  end function g0i
end program vci_stability_table
