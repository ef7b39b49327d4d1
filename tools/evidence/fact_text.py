"""How the evidence writes its numbers on the page: units, brackets, a section's run."""


def n_per_m(value):
    return "none" if value is None else f"{value:,.0f} N/m"


def run_info(data, section):
    block = data[section]
    return (f"{block['date']}, {block['seconds']:.0f} s, hapticd {block['hapticd']}, "
            f"{block['machine']['cpu']} ({block['machine']['cores']} cores, Linux "
            f"{block['machine']['kernel']})")


def bracket(low, high):
    return "no bracket" if low is None else f"{low:,.0f} to {high:,.0f} N/m"


def us(value):
    return "overflow" if value is None else f"{value:,.0f} us"


def mm(value_m):
    return f"{1e3 * value_m:.2f} mm"
