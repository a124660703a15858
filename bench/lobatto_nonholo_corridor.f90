!> Several impacts per step with a nonholonomic constraint (issue 25, Deliver 1): the knife edge in a
!> corridor (examples/scenes/vci_scene_knife_edge.f90) with Lobatto s = 1 ... 4 from the exact start,
!> against the closed form (knife_exact). Two ladders of step sizes per scene and s:
!>   several: h from above the largest time between impacts down to the mean, so that the steps span
!>            one or more impacts each on average over the whole ladder;
!>   fine:    h -> 0 below half the shortest time between impacts (the asymptotic range).
!> Printed per run: h, impacts per step (impacts h / T), the most impacts in one step, the errors of
!> the final configuration and of the impact times, error / h^2s; per ladder the least-squares slope
!> of log(error) against log(h).
!>
!>   vci_bench_lobatto_nonholo_corridor [CONDITION]   (hamiltonian (default) or discrete)
!>
!> Scenes: `corridor` (corridor_knife: walls +-0.1, spin 4, 7 impacts in 2 s, 0.22 ... 0.40 s apart;
!> test_knife_corridor_orders asserts its orders) and `narrow` (walls +-0.04, spin 1, from theta = 0.3:
!> 8 impacts in 1 s, 0.086 ... 0.156 s apart, 0.09 ... 0.16 rad of turn between two).
program bench_lobatto_nonholo_corridor
  use, intrinsic :: iso_fortran_env, only: output_unit
  use vci
  use vci_scene_knife_edge, only: knife_walls_t, knife_scene_t, knife_tracker_t, corridor_knife, knife_model, &
    knife_start, knife_exact
  implicit none
  integer, parameter :: nl = 8
  type(knife_scene_t), parameter :: narrow = knife_scene_t(1.0_dp, 1.0_dp, 0.3_dp, 0.04_dp)
  character(len=16) :: cond
  integer :: mode, sc, s, lad, i, nex, nimp, most
  real(dp) :: t_end, h(nl), es(nl), et(nl), qx(3), times(64), gap_min, gap_max
  real(dp) :: h_top, h_low, fac
  type(knife_scene_t) :: scene
  character(len=8) :: name
  cond = 'hamiltonian'
  if (command_argument_count() >= 1) call get_command_argument(1, cond)
  mode = merge(VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN, cond == 'discrete')
  do sc = 1, 2
    if (sc == 1) then
      scene = corridor_knife; t_end = 2.0_dp; name = 'corridor'
    else
      scene = narrow; t_end = 1.0_dp; name = 'narrow'
    end if
    call knife_exact(scene, t_end, 0.0_dp, qx, times, nex)
    gap_min = minval(times(2:nex) - times(1:nex - 1)); gap_max = maxval(times(2:nex) - times(1:nex - 1))
    write (output_unit, '(a,a,a,i0,a,f6.3,a,f6.3,a,f6.3,a,a)') 'scene ', trim(name), ': ', nex, &
      ' impacts, time between two ', gap_min, ' ... ', gap_max, ' (mean ', t_end / nex, '), condition ', trim(cond)
    do s = 1, 4
      do lad = 1, 2
        if (lad == 1) then
          ! from 0.5 (corridor: 1.75 impacts per step) or 0.4 (narrow: 3.2) down to the mean time
          ! between impacts: >= 1 impact per step on average over the whole ladder
          h_top = merge(0.5_dp, 0.4_dp, sc == 1); h_low = t_end / nex
          fac = (h_top / h_low)**(1.0_dp / (nl - 1))
        else if (sc == 1) then
          ! test_knife_corridor_orders' ladders (h <= 0.09, below half the shortest time between impacts)
          h_top = merge(0.05_dp, merge(0.07_dp, 0.09_dp, s == 3), s <= 2)
          fac = merge(merge(1.3_dp, 1.4_dp, s == 1), merge(1.25_dp, 1.1_dp, s == 3), s <= 2)
        else
          h_top = 0.04_dp; fac = 1.3_dp   ! (s = 3, 4 reach the round-off floor here: no slope)
        end if
        do i = 1, nl
          h(i) = h_top / fac**(i - 1)
          call run(h(i), es(i), et(i), nimp, most)
          write (output_unit, '(a,i0,1x,a,a,es10.3,a,f5.2,a,i0,a,2es10.2,a,2es10.2,a,i0)') '  s=', s, &
            trim(merge('several', 'fine   ', lad == 1)), ' h ', h(i), '  impacts/step ', nex * h(i) / t_end, &
            '  most in a step ', most, '  err state/times ', es(i), et(i), '  / h^2s ', es(i) / h(i)**(2 * s), &
            et(i) / h(i)**(2 * s), '  impacts found ', nimp
        end do
        write (output_unit, '(a,i0,1x,a,a,2f7.2)') '  s=', s, trim(merge('several', 'fine   ', lad == 1)), &
          ' least-squares order state/times ', slope(h, es), slope(h, et)
      end do
    end do
  end do
contains
  subroutine run(hh, err_state, err_times, nimp, most)
    real(dp), intent(inout) :: hh
    real(dp), intent(out) :: err_state, err_times
    integer, intent(out) :: nimp, most
    type(knife_walls_t), target :: knife
    type(knife_tracker_t), target :: tracker
    type(vci_integrator_t) :: integ
    real(dp) :: q0(3), p0(3)
    integer :: stat, nsteps, k
    knife = knife_model(scene)
    nsteps = nint(t_end / hh); hh = t_end / nsteps
    err_state = huge(1.0_dp); err_times = huge(1.0_dp); nimp = -1; most = 0
    call integ%create(knife, hh, stat)
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_LOBATTO, s, stat)
    if (stat == VCI_OK) call integ%set_tolerances(0.0_dp, 1.0e-15_dp, 30, stat)
    if (stat == VCI_OK) call integ%set_impact_energy(mode, stat)
    if (stat == VCI_OK) call integ%set_poke_samples(.true., stat)
    call knife_start(knife, scene, q0, p0)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    if (stat == VCI_OK) call integ%integrate(int(nsteps, i8), 1, stat, tracker)
    if (stat /= VCI_OK) then
      write (output_unit, '(a)') '  failed: '//integ%message(); return
    end if
    nimp = tracker%nimp
    err_state = maxval(abs(integ%configuration() - qx))
    if (nimp == nex) err_times = maxval(abs(tracker%times(1:nimp) - times(1:nimp)))
    do k = 1, nimp   ! impacts per step from the impact times (step index floor(t / h))
      most = max(most, count(floor(tracker%times(1:nimp) / hh) == floor(tracker%times(k) / hh)))
    end do
  end subroutine run

  pure real(dp) function slope(hh, err)
    real(dp), intent(in) :: hh(:), err(:)
    real(dp) :: x(size(hh)), y(size(hh))
    x = log(hh); y = log(err)
    slope = sum((x - sum(x) / size(x)) * (y - sum(y) / size(y))) / sum((x - sum(x) / size(x))**2)
  end function slope
end program bench_lobatto_nonholo_corridor
