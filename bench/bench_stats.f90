!> Statistics shared by the benchmark programs: the median of timed repeats (one definition, so
!> that every bench reports the same statistic).
module vci_bench_stats
  use vci, only: dp
  implicit none
  private
  public :: median

contains

  !> Median of x (the mean of the two middle values for an even count; 0 for none). Insertion
  !> sort on a copy: a bench's repeats number at most a few thousand.
  real(dp) function median(x)
    real(dp), intent(in) :: x(:)
    real(dp) :: y(size(x)), t
    integer :: i, j, n
    median = 0.0_dp
    n = size(x)
    if (n == 0) return
    y = x
    do i = 2, n
      t = y(i); j = i - 1
      do while (j >= 1)
        if (y(j) <= t) exit
        y(j + 1) = y(j); j = j - 1
      end do
      y(j + 1) = t
    end do
    if (mod(n, 2) == 1) then
      median = y((n + 1) / 2)
    else
      median = 0.5_dp * (y(n / 2) + y(n / 2 + 1))
    end if
  end function median
end module vci_bench_stats
