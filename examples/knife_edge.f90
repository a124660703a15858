!> A knife edge between two walls (issue 25's second nonholonomic scene, vci_scene_knife_edge): a
!> blade in the plane, q = (x, y, theta), that cannot slip sideways (sin theta x' - cos theta y' = 0),
!> between the walls x = +-0.8; from the origin at theta = 0.6 with speed 1 along the blade and spin
!> 1 it turns 2.7 and 3.6 rad between impacts (6 in 20 s). A continuous model discretised by
!> --scheme (default lobatto, --stages 4), started from the exact (q(0), p(0)); the summary ends with
!> the errors of the final state and of the impact times against the closed-form solution
!> (knife_exact) and the largest constraint residual at the step ends.
program knife_edge
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  use vci
  use vci_scene_knife_edge, only: knife_walls_t, knife_model, knife_start, knife_exact, knife_tracker_t, &
    turning_knife
  use vci_example_cli
  implicit none
  type(knife_walls_t), target :: model
  type(knife_tracker_t), target :: tracker
  type(example_options_t) :: opts
  opts%h = 0.2_dp; opts%t_final = 20.0_dp
  opts%scheme = 'lobatto'; opts%stages = 4
  call parse_options(opts, 'knife_edge', 'knife_edge: a knife edge between walls at x = +-0.8, against its '// &
    'exact solution (defaults h = 0.2, t-final = 20, --scheme lobatto --stages 4)')
  ! the comparison needs the exact start at t = 0, forward
  if (allocated(opts%from) .or. opts%backward .or. opts%start == 'pair') then
    write (error_unit, '(a)') 'knife_edge: --from, --backward and --start pair are not supported here '// &
      '(the run is compared with the exact solution from the exact start at t = 0)'
    stop 1, quiet=.true.
  end if
  if (opts%t_final < 0.0_dp) then
    write (error_unit, '(a)') 'knife_edge: --t-final must be >= 0'
    stop 1, quiet=.true.
  end if
  model = knife_model(turning_knife)
  call run_example('knife_edge', model, opts, init, tracker, report)
contains
  subroutine init(integ, stat)
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    real(dp) :: q0(3), p0(3)
    call knife_start(model, turning_knife, q0, p0)
    call integ%init_from_momentum(0.0_dp, q0, p0, stat)
  end subroutine init

  !> The errors against the closed form at the run's end time and the constraint residual.
  subroutine report(integ)
    type(vci_integrator_t), intent(in) :: integ
    real(dp), allocatable :: times(:), q(:), p(:)
    real(dp) :: qx(3), px(3), speed
    integer :: nex
    allocate (times(max(tracker%nimp, 1)))
    call knife_exact(turning_knife, integ%time(), 0.0_dp, qx, times, nex, speed=speed)
    px = [model%mass * speed * cos(qx(3)), model%mass * speed * sin(qx(3)), model%inertia * turning_knife%w]
    q = integ%configuration(); p = integ%momentum()
    write (output_unit, '(a,i0,a,i0)') 'impacts: ', tracker%nimp, '   exact: ', nex
    write (output_unit, '(a,es10.3,a,es10.3)') 'error against the exact solution: q ', maxval(abs(q - qx)), &
      '   p ', maxval(abs(p - px))
    if (tracker%nimp == nex .and. nex > 0) then
      write (output_unit, '(a,es10.3)') 'impact times: max error ', maxval(abs(tracker%times(1:nex) - times(1:nex)))
    else if (tracker%nimp /= nex) then
      write (output_unit, '(a)') 'impact times: not compared (the impact counts differ)'
    end if
    write (output_unit, '(a,es10.3)') 'largest constraint residual |Omega(q)^T qdot| / |qdot| at the step ends: ', &
      tracker%worst_residual
  end subroutine report
end program knife_edge
