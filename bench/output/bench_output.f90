!> Cost of HDF5 output per step: the paper's pendulum (h = 1e-4) integrated with no observer and with
!> the HDF5 writer (default flush interval, and every 100 steps) in the same process, alternating
!> the variants and keeping each one's best of several repetitions. Prints steps/s and the ratio.
!> Usage: vci_bench_output [STEPS [REPEATS [DIR]]]   (defaults 200000, 5, .)
program bench_output
  use vci
  use vci_hdf5_output, only: vci_hdf5_writer_t, VCI_HDF5_FLUSH_EVERY
  use vci_scene_pendulum, only: pendulum_t, pendulum_model
  implicit none
  type(pendulum_t), target :: model
  integer(i8) :: nsteps
  integer :: repeats, r, v
  character(len=256) :: arg, dir
  real(dp) :: best(3), secs
  integer, parameter :: flush_of(3) = [0, VCI_HDF5_FLUSH_EVERY, 100]

  nsteps = 200000_i8; repeats = 5; dir = '.'
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg); read (arg, *) nsteps
  end if
  if (command_argument_count() >= 2) then
    call get_command_argument(2, arg); read (arg, *) repeats
  end if
  if (command_argument_count() >= 3) call get_command_argument(3, dir)
  model = pendulum_model()
  best = huge(1.0_dp)
  do r = 1, repeats
    do v = 1, 3
      secs = run(flush_of(v))
      best(v) = min(best(v), secs)
    end do
  end do
  write (*, '(a,i0,a,i0,a)') 'pendulum, h = 1e-4, ', nsteps, ' steps, best of ', repeats, ' runs'
  write (*, '(a,es10.3,a)') 'no output:                 ', nsteps / best(1), ' steps/s'
  write (*, '(a,i0,a,es10.3,a,f6.3)') 'HDF5, flush every ', flush_of(2), ':   ', nsteps / best(2), &
    ' steps/s   ratio ', best(1) / best(2)
  write (*, '(a,i0,a,es10.3,a,f6.3)') 'HDF5, flush every ', flush_of(3), ':    ', nsteps / best(3), &
    ' steps/s   ratio ', best(1) / best(3)
contains
  !> Seconds for nsteps steps; flush_every = 0: no output.
  real(dp) function run(flush_every) result(secs)
    integer, intent(in) :: flush_every
    type(vci_integrator_t), target :: integ
    type(vci_hdf5_writer_t), target :: w
    real(dp) :: q0(2), qd(2), pi, h
    integer :: stat
    integer(i8) :: c0, c1, rate
    pi = acos(-1.0_dp); h = 1.0e-4_dp
    q0 = [0.75_dp * pi, 0.0_dp]
    qd = [pi / 4.0_dp, (pi + 0.5_dp) * pi / 4.0_dp]
    call integ%create(model, h, stat)
    call integ%init_from_pair(0.0_dp, q0, q0 + h * qd, stat)
    call system_clock(c0, rate)
    if (flush_every > 0) then
      call w%open(trim(dir)//'/bench_output.h5', stat, overwrite=.true., scene='pendulum', flush_every=flush_every)
      if (stat /= VCI_OK) error stop 'bench_output: cannot open the output file'
      call integ%integrate(nsteps, 1, stat, w)
    else
      call integ%integrate(nsteps, 1, stat)
    end if
    call system_clock(c1)
    if (stat /= VCI_OK) error stop 'bench_output: the run failed'
    secs = real(c1 - c0, dp) / real(rate, dp)
  end function run
end program bench_output
