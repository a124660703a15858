!> Downstream check of an installed MPI-enabled vci: a ball dropped on the floor from six heights,
!> run as an ensemble over the ranks into one HDF5 file, read back on rank 0 and compared with the
!> same ensemble run in memory; exits nonzero unless bitwise equal and the bounce times are right.
module ball_model
  use vci
  implicit none
  type, extends(vci_model_t) :: ball_t
  contains
    procedure :: d1, d2, d3, gaps
  end type ball_t
contains
  subroutine d1(self, q, v, h, out, stat)
    class(ball_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = -(v - q) / h - 0.5_dp * h * 9.8_dp
  end subroutine d1
  subroutine d2(self, q, v, h, out, stat)
    class(ball_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = (v - q) / h - 0.5_dp * h * 9.8_dp
  end subroutine d2
  subroutine d3(self, q, v, h, out, stat)
    class(ball_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    out = -0.5_dp * sum((v - q)**2) / h**2 - 4.9_dp * (q(1) + v(1))
  end subroutine d3
  subroutine gaps(self, q, g, stat)
    class(ball_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = q(1)
  end subroutine gaps
end module ball_model

program ens_export
  use mpi_f08
  use vci
  use vci_ensemble
  use vci_ensemble_h5, only: vci_ensemble_read
  use vci_ensemble_mpi, only: vci_ensemble_run_file
  use ball_model
  implicit none
  type(vci_prototype_factory_t) :: factory
  type(vci_ensemble_config_t) :: cfg
  type(vci_ensemble_table_t) :: table
  type(vci_ensemble_results_t) :: from_file, in_memory
  type(ball_t) :: ball
  character(len=512) :: msg
  integer :: stat, ierr, provided, rank, i
  real(dp) :: height, t_first
  call MPI_Init_thread(MPI_THREAD_FUNNELED, provided, ierr)
  call MPI_Comm_rank(MPI_COMM_WORLD, rank, ierr)
  ball%n = 1; ball%n_gaps = 1
  allocate (factory%prototype, source=ball)
  allocate (table%t0(6), table%q0(1, 6), table%v0(1, 6))
  do i = 1, 6            ! dropped at rest from 1, 1.5, ... 3.5 m: the pair q(-h/2) = q(h/2)
    table%t0(i) = -0.5e-3_dp; table%q0(1, i) = 0.5_dp + 0.5_dp * i; table%v0(1, i) = table%q0(1, i)
  end do
  cfg%h = 1.0e-3_dp; cfg%nsteps = 1500; cfg%impact_cap = 4
  call vci_ensemble_run_file(factory, cfg, table, 'export_ensemble.h5', stat, msg, overwrite=.true.)
  if (stat /= VCI_OK) then
    print '(a)', trim(msg); call MPI_Abort(MPI_COMM_WORLD, 1, ierr)
  end if
  if (rank == 0) then
    call vci_ensemble_read('export_ensemble.h5', from_file, stat, msg)
    call vci_ensemble_run(factory, cfg, table, in_memory, stat, msg)
    if (any(transfer(from_file%q, [0_i8]) /= transfer(in_memory%q, [0_i8])) .or. &
        any(transfer(from_file%impact_t, [0_i8]) /= transfer(in_memory%impact_t, [0_i8]))) then
      print '(a)', 'FAIL: file and in-memory ensemble differ'; call MPI_Abort(MPI_COMM_WORLD, 1, ierr)
    end if
    do i = 1, 6
      ! the first bounce at sqrt(2 H / g); the midpoint rule's impact time is second order in h
      height = table%q0(1, i); t_first = sqrt(2.0_dp * height / 9.8_dp)
      if (abs(from_file%impact_t(1, i) - t_first) > 1.0e-5_dp) then
        print '(a,i0,2es14.6)', 'FAIL: first bounce of member ', i, from_file%impact_t(1, i), t_first
        call MPI_Abort(MPI_COMM_WORLD, 1, ierr)
      end if
    end do
    print '(a)', 'installed MPI-enabled vci: ensemble file equals the in-memory run; bounce times right'
  end if
  call MPI_Finalize(ierr)
end program ens_export
