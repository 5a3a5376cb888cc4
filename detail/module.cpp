// Translation unit that keeps the module non-empty; algorithms live in the other files.
