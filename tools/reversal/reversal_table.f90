!> Reversal error of the ellipse against the number of steps: N steps forward with the (+) scheme,
!> N back with the (-) scheme, relative distance to the start. Prints a markdown table.
!> Run: build/bin/vci_reversal_table (built with the tests); docs/BACKWARD.md holds its output.
program reversal_table
  use vci
  use vci_scene_ellipse, only: ellipse_t, ellipse_model
  use vci_test_scenes, only: start_ellipse
  implicit none
  type(ellipse_t), target :: model
  type(vci_integrator_t) :: integ
  integer :: stat, i, n
  integer(i8) :: impacts
  real(dp) :: q0(3), p0(3)
  type(vci_stats_t) :: stats
  type(vci_settings_t) :: settings
  integer, parameter :: ns(8) = [100, 200, 300, 400, 500, 600, 700, 800]
  model = ellipse_model()
  print '(a)', '| N steps | impacts | rel. error q | rel. error p | scaled Newton residual tolerance |'
  print '(a)', '|---:|---:|---:|---:|---:|'
  do i = 1, size(ns)
    n = ns(i)
    call start_ellipse(integ, model, 1.0e-2_dp, stat)
    q0 = integ%configuration(); p0 = integ%momentum(); settings = integ%settings()
    call integ%integrate(int(n, i8), 1, stat)
    stats = integ%statistics(); impacts = stats%impacts
    if (stat == VCI_OK) call integ%integrate(int(n, i8), -1, stat)
    if (stat /= VCI_OK) then
      print '(a)', 'failed: '//integ%message(); cycle
    end if
    print '(a,i0,a,i0,a,es9.2,a,es9.2,a,es8.1,a)', '| ', n, ' | ', impacts, ' | ', norm2(integ%configuration() - q0) / norm2(q0), &
      ' | ', norm2(integ%momentum() - p0) / norm2(p0), ' | ', settings%rtol, ' |'
  end do
end program reversal_table
