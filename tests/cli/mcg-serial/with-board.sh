# with-board.sh COMMAND...: runs COMMAND with the emulated board (mcg-sim --board) behind ./ttyB in
# the case's directory; the board ends with it. Exit status: COMMAND's.
mcg-sim --board ./ttyB > /dev/null 2>&1 &
board=$!
i=0
while [ ! -e ./ttyB ] && [ $i -lt 100 ]; do
  sleep 0.1
  i=$((i + 1))
done
"$@"
status=$?
kill $board
wait $board 2> /dev/null
exit $status
