!> The reversal property over random scenes (issue 24, item 1), longer than the default suite's
!> fixed seeds (test/core/test_reversal.pf): for each seed, a box scene with L quartic in the
!> velocity, a magnetic term, gravity and a spring, N steps forward and N back must return the
!> start to solver tolerance, with the same impacts and the same energy fallbacks in both
!> directions (test/support/vci_test_reversal.f90). Prints one line per failing seed and a summary.
!>
!>   vci_reversal_fuzz SEED_FIRST SEED_COUNT [SECONDS [TOL [firm|wide [impacts]]]]   (defaults: 60 s, 1e-9, firm)
!>
!> impacts: also print each seed's forward impacts (condition, impulse, normal velocities)
!>
!> firm: impacts away from grazes (the property the default suite asserts); wide: soft impacts too
!> A seed whose only fault is its distance to the start (status OK, the same impacts and fallbacks
!> both ways) is judged against its forward growth: how much the forward run amplifies a start
!> moved by 1e-9 and by 1e-10 relative (vci_test_reversal: forward_growth; the smaller of the two,
!> and only where they agree within a factor 2: linear growth), times the solver's rtol (1e-12). An error below that is the scene's chaos acting on the solves'
!> tolerance (counted as chaotic, not failed; docs/BACKWARD.md); above it, or above 1e-6, a failure.
!>
!> Exit status 1 when a seed failed.
program vci_reversal_fuzz
  use vci
  use vci_test_reversal
  implicit none
  integer :: first, count, seed, failed, run, multi, fallbacks, soft, untied
  real(dp) :: seconds, tol, worst_q, worst_p, chaos_bound, g9, g10
  real(dp), parameter :: rtol = 1.0e-12_dp    ! the integrator's default Newton tolerance
  integer :: chaotic
  integer(i8) :: c0, c1, rate
  character(len=64) :: arg
  type(reversal_scene_t) :: s
  type(reversal_result_t) :: r
  logical :: bad, firm, list_impacts
  first = 1; count = 100; seconds = 60.0_dp; tol = 1.0e-9_dp; firm = .true.
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg); read (arg, *) first
  end if
  if (command_argument_count() >= 2) then
    call get_command_argument(2, arg); read (arg, *) count
  end if
  if (command_argument_count() >= 3) then
    call get_command_argument(3, arg); read (arg, *) seconds
  end if
  if (command_argument_count() >= 4) then
    call get_command_argument(4, arg); read (arg, *) tol
  end if
  if (command_argument_count() >= 5) then
    call get_command_argument(5, arg); firm = trim(arg) /= 'wide'
  end if
  list_impacts = .false.
  if (command_argument_count() >= 6) then
    call get_command_argument(6, arg); list_impacts = trim(arg) == 'impacts'
  end if
  call system_clock(c0, rate)
  chaotic = 0
  failed = 0; soft = 0; untied = 0; run = 0; multi = 0; fallbacks = 0; worst_q = 0.0_dp; worst_p = 0.0_dp
  do seed = first, first + count - 1
    s = random_scene(seed, firm)
    r = round_trip(s)
    run = run + 1
    if (list_impacts) then
      print '(a,i0,a,a)', 'seed ', seed, ': ', trim(scene_label(s))
      call print_forward_impacts(s)
    end if
    bad = r%stat /= VCI_OK
    if (.not. bad) bad = .not. (r%err_q <= tol .and. r%err_p <= tol) .or. r%impacts_fwd /= r%impacts_bwd &
                         .or. r%fallbacks_fwd /= r%fallbacks_bwd
    if (r%stat == VCI_OK) then
      worst_q = max(worst_q, r%err_q); worst_p = max(worst_p, r%err_p)
      multi = multi + r%multi_steps; fallbacks = fallbacks + r%fallbacks_fwd
    end if
    chaos_bound = -1.0_dp; g9 = -1.0_dp; g10 = -1.0_dp
    if (bad .and. r%stat == VCI_OK .and. r%impacts_fwd == r%impacts_bwd .and. r%fallbacks_fwd == r%fallbacks_bwd) then
      ! only where the growth is linear (the two perturbations' growths within a factor 2: a
      ! perturbation that changes a branch at an impact gives O(1) / eps instead), and at most
      ! 1e-6 (a different branch at an impact, 1e-3 to 1 off, never passes as chaos)
      g9 = forward_growth(s, 1.0e-9_dp); g10 = forward_growth(s, 1.0e-10_dp)
      if (g9 > 0.0_dp .and. g10 > 0.0_dp .and. max(g9, g10) <= 2.0_dp * min(g9, g10)) &
        chaos_bound = min(1.0e-6_dp, rtol * min(g9, g10))
      if (max(r%err_q, r%err_p) <= chaos_bound) chaotic = chaotic + 1
    end if
    if (bad .and. .not. max(r%err_q, r%err_p) <= chaos_bound) then
      failed = failed + 1
      if (r%fallbacks_fwd + r%fallbacks_bwd + r%touches > 0) soft = soft + 1
      if (r%irreversible > 0) untied = untied + 1
      print '(a,i0,a,a)', 'seed ', seed, ': ', trim(scene_label(s))
      print '(a,i0,a,es10.3,a,es10.3,a,i0,a,i0,a,i0,a,i0,a,i0,a,i0,a,a)', '  stat ', r%stat, ' err q ', r%err_q, ' p ', &
        r%err_p, ' impacts ', r%impacts_fwd, '/', r%impacts_bwd, ' fallbacks ', r%fallbacks_fwd, '/', r%fallbacks_bwd, &
        ' touches ', r%touches, ' irreversible ', r%irreversible, ' ', trim(r%message)
      if (chaos_bound > 0.0_dp) print '(a,es9.2,a)', '  forward growth x rtol ', chaos_bound, &
        ' (a start moved by 1e-9 and 1e-10, relative; at most 1e-6): beyond it'
      if (g9 > 0.0_dp .and. chaos_bound < 0.0_dp) print '(a,2es9.2,a)', '  forward growth ', g9, g10, &
        ' (a start moved by 1e-9, 1e-10): not linear, not judged as chaos'
    else if (bad) then
      print '(a,i0,a,es9.2,a,es9.2,a)', 'seed ', seed, ': chaotic (err ', max(r%err_q, r%err_p), &
        ' within forward growth x rtol ', chaos_bound, ')'
    end if
    call system_clock(c1)
    if (real(c1 - c0, dp) / real(rate, dp) > seconds) exit
  end do
  print '(a,i0,a,i0,a,i0,a,i0,a,i0,a,i0,a,es9.2,a,es9.2,a,i0,a)', 'seeds run ', run, ', failed ', failed, ' (', soft, &
    ' with a fallback or a touch, ', untied, ' with an irreversible impact), steps with several impacts ', multi, &
    ', fallbacks ', fallbacks, &
    ', worst err q ', worst_q, ' p ', worst_p, ', ', chaotic, ' chaotic (beyond TOL, within forward growth x rtol)'
  if (failed > 0) error stop 1
end program vci_reversal_fuzz
