!> Cost of HDF5 output per step: the paper's pendulum (h = 1e-4) integrated with no observer and with
!> the HDF5 writer (default flush interval, every 100 steps, gzip levels 1 and 4 with shuffle, every
!> 10th state) in the same process, alternating the variants and keeping each one's best of several
!> repetitions. Prints steps/s, the ratio to no output and the file's size.
!> Usage: vci_bench_output [STEPS [REPEATS [DIR [VARIANT]]]]   (defaults 200000, 5, ., all)
!> VARIANT (1..6) runs only that one, once per repeat: for instruction counts under callgrind.
program bench_output
  use vci_tool_args, only: arg_value
  use vci
  use vci_hdf5_output, only: vci_hdf5_writer_t, VCI_HDF5_FLUSH_EVERY
  use vci_scene_pendulum, only: pendulum_t, pendulum_model
  implicit none
  type(pendulum_t), target :: model
  integer(i8) :: nsteps, bytes(6)
  integer :: repeats, r, v, only
  character(len=256) :: dir
  real(dp) :: best(6), secs
  ! variant: flush interval (0: no output), gzip level, every k-th state
  integer, parameter :: flush_of(6) = [0, VCI_HDF5_FLUSH_EVERY, 100, VCI_HDF5_FLUSH_EVERY, VCI_HDF5_FLUSH_EVERY, &
                                       VCI_HDF5_FLUSH_EVERY]
  integer, parameter :: gzip_of(6) = [0, 0, 0, 1, 4, 0]
  integer, parameter :: every_of(6) = [1, 1, 1, 1, 1, 10]
  character(len=36), parameter :: name_of(6) = [character(len=36) :: 'no output', &
    'HDF5, flush every 4096 (default)', 'HDF5, flush every 100', 'HDF5, gzip 1 + shuffle (--compress)', &
    'HDF5, gzip 4 + shuffle', 'HDF5, every 10th state (--every 10)']

  nsteps = 200000_i8; repeats = 5; dir = '.'; only = 0
  if (command_argument_count() >= 1) then
    call arg_value(1, 'NSTEPS', nsteps)
  end if
  if (command_argument_count() >= 2) then
    call arg_value(2, 'REPEATS', repeats)
  end if
  if (command_argument_count() >= 3) call get_command_argument(3, dir)
  if (command_argument_count() >= 4) then
    call arg_value(4, 'ONLY', only)
  end if
  model = pendulum_model()
  best = huge(1.0_dp); bytes = 0
  do r = 1, repeats
    do v = 1, 6
      if (only /= 0 .and. v /= only) cycle
      secs = run(v, bytes(v))
      best(v) = min(best(v), secs)
    end do
  end do
  write (*, '(a,i0,a,i0,a)') 'pendulum, h = 1e-4, ', nsteps, ' steps, best of ', repeats, ' runs'
  write (*, '(a38,a12,a8,a12)') 'variant', 'steps/s', 'ratio', 'file bytes'
  do v = 1, 6
    if (only /= 0 .and. v /= only) cycle
    write (*, '(a38,es12.3,f8.3,i12)') name_of(v), nsteps / best(v), best(1) / best(v), bytes(v)
  end do
contains
  !> Seconds for nsteps steps with variant v, and the size of its file.
  real(dp) function run(v, size_bytes) result(secs)
    integer, intent(in) :: v
    integer(i8), intent(out) :: size_bytes
    type(vci_integrator_t), target :: integ
    type(vci_hdf5_writer_t), target :: w
    real(dp) :: q0(2), qd(2), pi, h
    integer :: stat
    integer(i8) :: c0, c1, rate
    character(len=:), allocatable :: path
    pi = acos(-1.0_dp); h = 1.0e-4_dp
    q0 = [0.75_dp * pi, 0.0_dp]
    qd = [pi / 4.0_dp, (pi + 0.5_dp) * pi / 4.0_dp]
    call integ%create(model, h, stat)
    call integ%init_from_pair(0.0_dp, q0, q0 + h * qd, stat)
    path = trim(dir)//'/bench_output.h5'
    size_bytes = 0
    call system_clock(c0, rate)
    if (flush_of(v) > 0) then
      call w%open(path, stat, overwrite=.true., scene='pendulum', flush_every=flush_of(v), &
                  compress=gzip_of(v), every=every_of(v))
      if (stat /= VCI_OK) error stop 'bench_output: cannot open the output file'
      call integ%integrate(nsteps, 1, stat, w)
    else
      call integ%integrate(nsteps, 1, stat)
    end if
    call system_clock(c1)
    if (stat /= VCI_OK) error stop 'bench_output: the run failed'
    secs = real(c1 - c0, dp) / real(rate, dp)
    if (flush_of(v) > 0) inquire (file=path, size=size_bytes)
  end function run
end program bench_output
