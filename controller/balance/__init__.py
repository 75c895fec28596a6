"""The balance controller: a free-root character that follows a reference motion with no
external force (whole-body QP, foot placement, foot tilt, lookahead gain selection and a
backtracking search), and the record of what each run did."""
